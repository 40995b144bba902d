"""Bad input gives the documented exception, with a message naming the input."""

import numpy as np
import pytest

import mgn


def test_exception_hierarchy_maps_to_builtins():
    assert issubclass(mgn.InvalidArgumentError, mgn.MgnError)
    assert issubclass(mgn.InvalidArgumentError, ValueError)
    assert issubclass(mgn.IoError, OSError)
    assert issubclass(mgn.UnsupportedError, ValueError)
    assert issubclass(mgn.BackendError, RuntimeError)


def test_missing_file(data_dir):
    path = data_dir / "no_such_mesh.obj"
    with pytest.raises(mgn.IoError, match=r"no_such_mesh.obj"):
        mgn.load_mesh(path)


def test_text_file_named_obj(data_dir):
    with pytest.raises(mgn.IoError, match=r"not_a_mesh.obj"):
        mgn.load_mesh(data_dir / "not_a_mesh.obj")


def test_empty_mesh_file(data_dir):
    with pytest.raises(mgn.MgnError, match=r"empty.stl"):
        mgn.load_mesh(data_dir / "empty.stl")


def test_empty_mesh_arrays_are_refused_by_every_consumer():
    empty = mgn.Mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int32), name="nothing")
    for call in (
        lambda: mgn.mass_properties(empty),
        lambda: mgn.sample_surface(empty, 10),
        lambda: mgn.RayScene([empty]),
        lambda: mgn.CollisionModel(empty),
    ):
        with pytest.raises(mgn.InvalidArgumentError, match="no faces"):
            call()


def test_nan_vertices(data_dir):
    with pytest.raises(mgn.InvalidArgumentError, match=r"nan_vertex.obj.*not finite"):
        mgn.load_mesh(data_dir / "nan_vertex.obj")
    v = np.array([[0, 0, 0], [1, 0, 0], [0, np.nan, 0]], np.float32)
    with pytest.raises(mgn.InvalidArgumentError, match="vertex 2 is not finite"):
        mgn.Mesh(v, np.array([[0, 1, 2]]), name="bad")


def test_zero_area_faces(data_dir):
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], np.float32)
    with pytest.raises(mgn.InvalidArgumentError, match=r"'flat'.*zero area"):
        mgn.Mesh(v, np.array([[0, 1, 2]]), name="flat")
    with pytest.raises(mgn.InvalidArgumentError, match=r"zero_area.obj.*zero area"):
        mgn.load_mesh(data_dir / "zero_area.obj", drop_degenerate=False)
    assert mgn.load_mesh(data_dir / "zero_area.obj").num_faces == 4  # dropped by default


def test_out_of_range_index_and_bad_shapes():
    v = np.zeros((3, 3), np.float32)
    with pytest.raises(mgn.InvalidArgumentError, match="references vertex 5"):
        mgn.Mesh(v, np.array([[0, 1, 5]]))
    with pytest.raises(mgn.InvalidArgumentError, match=r"vertices: expected .* \(N, 3\)"):
        mgn.Mesh(np.zeros((3, 2)), np.array([[0, 1, 2]]))


def test_negative_density_and_bad_thickness():
    box = mgn.make_box([0.1, 0.1, 0.1])
    with pytest.raises(mgn.InvalidArgumentError, match=r"density.*-5"):
        mgn.mass_properties(box, -5.0)
    with pytest.raises(mgn.InvalidArgumentError, match="density"):
        mgn.mass_properties(box, float("nan"))


def test_bad_poses_are_named():
    box = mgn.make_box([0.1, 0.1, 0.1])
    model = mgn.CollisionModel(box)
    poses = np.stack([np.eye(4)] * 3)
    poses[1, 0, 3] = np.nan
    with pytest.raises(mgn.InvalidArgumentError, match=r"X_WB\[1\].*non-finite"):
        mgn.collide(model, np.eye(4), model, poses)
    sheared = np.eye(4)
    sheared[0, 1] = 0.5
    with pytest.raises(mgn.InvalidArgumentError, match="not a proper rotation"):
        mgn.RayScene([box], poses=sheared[None])
    with pytest.raises(mgn.InvalidArgumentError, match="X_WA: expected shape"):
        mgn.collide(model, np.eye(3), model, np.eye(4))


def test_bad_rays_and_options():
    scene = mgn.RayScene([mgn.make_box([0.1, 0.1, 0.1])])
    o = np.zeros((2, 3), np.float32)
    with pytest.raises(mgn.InvalidArgumentError, match="zero direction"):
        scene.intersect(o, np.zeros((2, 3)))
    with pytest.raises(mgn.InvalidArgumentError, match="same number of rays"):
        scene.intersect(o, np.ones((3, 3)))
    with pytest.raises(mgn.InvalidArgumentError, match="num_threads"):
        scene.intersect(o, np.ones((2, 3)), num_threads=-1)
    with pytest.raises(mgn.InvalidArgumentError, match="method"):
        mgn.sample_surface(mgn.make_box([1, 1, 1]), 3, method="poisson")
