"""A keypoint is visible only on its own surface and unoccluded (issue 16, item 11): hand-placed
keypoints that float (a hole centre, a point above the object) are not visible, even when the ray
towards them reaches whatever lies behind."""

from __future__ import annotations

import numpy as np
from conftest import translation
from test_view_labels import render_ids, top_down

from mgn.geometry import make_box
from mgn.view_labels import SceneRayModel, view_object_labels


def test_floating_keypoints_are_not_visible() -> None:
    # A: a 10 cm cube on the floor box B (top face of A at z = 0.15, of B at z = 0.05). The camera
    # looks straight down from z = 1.
    a, b = make_box([0.1, 0.1, 0.1]), make_box([0.3, 0.3, 0.05])
    Xa, Xb = translation(0.0, 0.0, 0.1), translation(0.0, 0.0, 0.025)
    ids = render_ids(top_down(), [(a, Xa, 1), (b, Xb, 2)])
    kp_a = [
        [1, 0.02, 0.01, 0.05],  # on A's top face: visible
        [2, 0.02, 0.01, 0.058],  # 8 mm above A's top face, in free space: floats
        [3, 0.0, 0.0, 0.0],  # A's centre, inside the solid (a "hole centre"): not on the surface
        [4, 0.08, 0.0, -0.05],  # off A, at the height of B's top face: B is seen there, not A
    ]
    kp_b = [[1, 0.12, 0.0, 0.025], [2, 0.0, 0.0, 0.025]]  # B's top: free / under A
    model = SceneRayModel([a, b], np.stack([Xa, Xb]), [1, 2], keypoints=[kp_a, kp_b])
    L = view_object_labels(model, top_down(), ids)
    visible = {(int(o), int(k)) for o, k in zip(L.keypoint_object, L.keypoints[:, 0], strict=True)}
    hidden = {
        (int(o), int(k))
        for o, k in zip(L.occluded_keypoint_object, L.occluded_keypoints[:, 0], strict=True)
    }
    assert visible == {(0, 1), (1, 1)}
    assert hidden == {(0, 2), (0, 3), (0, 4), (1, 2)}
