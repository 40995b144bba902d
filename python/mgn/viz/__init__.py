"""Pictures for people: mesh snapshots, dataset overlays, the HTML report, trial pictures.

- :mod:`mgn.viz.pictures`: shaded ray-cast snapshot of a mesh with coloured points, score colours.
- :mod:`mgn.viz.overlay`: ``mgn show``, one view of a dataset with its labels drawn.
- :mod:`mgn.viz.report`: ``mgn report``, a self-contained HTML page about a dataset.
- :mod:`mgn.viz.shake_trial`: the picture of one parallel-jaw shake trial.
- :mod:`mgn.viz.suction_compare`: the three seal models side by side (``mgn suction compare``).
"""
