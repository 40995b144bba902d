"""`mgn scene render`: a hand-placed scene JSON rendered from the 37-view rig."""

import numpy as np
from PIL import Image

from mgn.cli.main import main
from mgn.io.scene_json import write_scene_json
from mgn.objects import ToteSpec, get_object
from mgn.scene.scene import Scene, SceneInstance


def test_render_writes_the_views_and_sees_the_object(tmp_path, capsys):
    spec = get_object("box_cube")
    X = np.eye(4)
    X[2, 3] = 0.5 * float(spec.extents[2])  # resting on the tote floor, at the centre
    inst = SceneInstance(1, spec.name, spec.category_id, "builtin", X, ("floor",))
    write_scene_json(Scene((inst,), ToteSpec(), seed=3), tmp_path / "scene.json")
    out = tmp_path / "views"
    args = ["scene", "render", str(tmp_path / "scene.json"), "--view", "0", "7", "--out", str(out)]
    assert main([*args, "--sensor", "ideal"]) == 0
    assert "view 7" in capsys.readouterr().out
    for v in (0, 7):
        with Image.open(out / f"{v}_rgb.png") as im:
            assert im.size == (1200, 1200)
        with Image.open(out / f"{v}_instances.png") as im:
            ids = np.asarray(im)
        assert set(np.unique(ids)) == {0, 1}
    # View 0 looks straight down at the tote centre: the cube is in the middle of the image.
    with Image.open(out / "0_instances.png") as im:
        ids = np.asarray(im)
    assert ids[600, 600] == 1 and ids[5, 5] == 0


def test_render_rejects_an_empty_scene(tmp_path, capsys):
    write_scene_json(Scene((), ToteSpec(), seed=0), tmp_path / "empty.json")
    assert main(["scene", "render", str(tmp_path / "empty.json"), "--out", str(tmp_path)]) != 0
    assert "no objects" in capsys.readouterr().err
