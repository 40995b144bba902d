"""The one unit conversion of mgn: metres inside, centimetres in MetaGraspNet files.

Everything in mgn is SI (m, kg, s, rad). MetaGraspNet stores lengths in centimetres (depth
images, grasp contacts and widths, keypoints, scene_gt translations, layout depth differences);
the readers and writers of :mod:`mgn.io` convert with :data:`M_TO_CM` at the file boundary.
"""

from __future__ import annotations

__all__ = ["M_TO_CM"]

#: Centimetres per metre: ``cm = m * M_TO_CM``, ``m = cm / M_TO_CM``.
M_TO_CM = 100.0
