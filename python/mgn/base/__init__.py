"""Layer 0, core helpers every other layer may use: atomic and byte-reproducible file writes.

- :mod:`mgn.base.atomic`: write a file or a folder so that readers see all of it or nothing.
- :mod:`mgn.base.core_result`: dataclasses filled from the compiled core's result classes.
- :mod:`mgn.base.deterministic`: ``.npz`` and HDF5 writes whose bytes do not depend on the clock.

Together with :mod:`mgn.errors` and the compiled core ``mgn._core`` this is the bottom layer of
the package (docs/architecture.md); it imports nothing else from mgn.
"""
