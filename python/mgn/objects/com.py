"""Centre-of-mass keypoints of an object: surface points scored by their closeness to the
object's centre of mass (the MetaGraspNet CoM label, written to each ``models/<id>/`` folder)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from mgn.geometry import mesh as geo

__all__ = ["NUM_COM_KEYPOINTS", "com_keypoints"]

#: Number of centre-of-mass keypoints per object (MetaGraspNet).
NUM_COM_KEYPOINTS = 1000


def com_keypoints(mesh: geo.Mesh, density: float, *, seed: int) -> npt.NDArray[np.float64]:
    """(1000, 4) [score, x, y, z] in metres: surface points scored by closeness to the CoM.

    score = (d_max - d) / (d_max - d_min), d = distance to the mass-weighted centre of mass.
    Points are spread evenly (blue noise) with a fixed ``seed``.
    """
    com = geo.mass_properties(mesh, density).center_of_mass
    pts = geo.sample_surface(mesh, NUM_COM_KEYPOINTS, method="even", seed=seed).points.astype(
        np.float64
    )
    d = np.linalg.norm(pts - com, axis=1)
    span = max(float(d.max() - d.min()), 1e-12)
    score = (d.max() - d) / span
    return np.column_stack([score, pts])
