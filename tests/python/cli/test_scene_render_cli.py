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
    assert ids[600, 600] == 1
    assert ids[5, 5] == 0


def test_render_rejects_an_empty_scene(tmp_path, capsys):
    write_scene_json(Scene((), ToteSpec(), seed=0), tmp_path / "empty.json")
    assert main(["scene", "render", str(tmp_path / "empty.json"), "--out", str(tmp_path)]) != 0
    assert "no objects" in capsys.readouterr().err


def test_render_applies_the_config_camera_section(tmp_path):
    # `mgn scene label` takes the cameras from the config's camera section; `mgn scene render`
    # with the same --config must render the same cameras: the user's 96 x 72 intrinsics (not
    # the default 1200 x 1200), the ideal sensor (no holes) and the configured views.
    spec = get_object("box_cube")
    X = np.eye(4)
    X[2, 3] = 0.5 * float(spec.extents[2])
    inst = SceneInstance(1, spec.name, spec.category_id, "builtin", X, ("floor",))
    write_scene_json(Scene((inst,), ToteSpec(), seed=3), tmp_path / "scene.json")
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(
        "camera:\n"
        "  intrinsics: {width: 96, height: 72, fx: 80.0, fy: 80.0, cx: 48.0, cy: 36.0}\n"
        "  sensor: ideal\n"
        "  views: [0, 4]\n"
    )
    out = tmp_path / "views"
    assert (
        main(
            [
                "scene",
                "render",
                str(tmp_path / "scene.json"),
                "--config",
                str(cfg),
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert sorted(p.name for p in out.glob("*_rgb.png")) == ["0_rgb.png", "4_rgb.png"]
    with Image.open(out / "0_rgb.png") as im:
        assert im.size == (96, 72)
    with np.load(out / "0_depth.npz") as z:
        assert z["depth"].shape == (72, 96)
        assert bool(z["valid_depth"][36, 48])
    with Image.open(out / "0_instances.png") as im:
        assert np.asarray(im)[36, 48] == 1  # the cube below the centre of the top view
    # Flags override the config: one view, 0.5 x the resolution of the config's camera.
    cfg.write_text(cfg.read_text() + "  resolution_scale: 0.5\n")
    assert (
        main(
            [
                "scene",
                "render",
                str(tmp_path / "scene.json"),
                "--config",
                str(cfg),
                "--view",
                "2",
                "--out",
                str(tmp_path / "v2"),
            ]
        )
        == 0
    )
    with Image.open(tmp_path / "v2" / "2_rgb.png") as im:
        assert im.size == (48, 36)
    assert (
        main(
            [
                "scene",
                "render",
                str(tmp_path / "scene.json"),
                "--view",
                "37",
                "--out",
                str(tmp_path / "bad"),
            ]
        )
        == 1
    )


def test_show_says_when_the_folder_does_not_exist(tmp_path, capsys):
    missing = tmp_path / "nonexistent"
    assert main(["show", str(missing), "--view", "3", "-o", str(tmp_path / "v.png")]) == 1
    err = capsys.readouterr().err
    assert f"'{missing}' does not exist" in err
    assert "--scene" not in err.split("exist")[0]
    (tmp_path / "empty").mkdir()
    assert main(["show", str(tmp_path / "empty"), "-o", str(tmp_path / "v.png")]) == 1
    assert "holds no views" in capsys.readouterr().err


def test_physics_grasps_zero_says_how_physics_is_switched_off():
    import pytest

    from mgn.pipeline.config import ConfigError, load_config

    with pytest.raises(
        ConfigError, match=r"object_labels\.physics_grasps.*labels\.pj_physics: false"
    ):
        load_config({"object_labels": {"physics_grasps": 0}})
    assert load_config({"labels": {"pj_physics": False}}).labels.pj_physics is False
