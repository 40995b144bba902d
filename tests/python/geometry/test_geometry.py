"""Mesh loading, validation, mass properties and sampling against analytic truth."""

import numpy as np
import pytest

import mgn


@pytest.mark.parametrize("name", ["cube.obj", "cube.stl", "cube.ply", "cube.glb", "cube.dae"])
def test_every_format_loads_as_a_closed_2cm_cube(data_dir, name):
    mesh = mgn.load_mesh(data_dir / name)
    report = mesh.validate()
    assert report.is_watertight
    assert report.is_outward
    np.testing.assert_allclose(mesh.bounds, [[-0.01] * 3, [0.01] * 3], atol=1e-7)
    assert mgn.mass_properties(mesh).volume == pytest.approx(8e-6, rel=1e-5)


def test_obj_material_texture_and_uvs(data_dir):
    mesh = mgn.load_mesh(data_dir / "cube.obj")
    (mat,) = mesh.materials
    np.testing.assert_allclose(mat.base_color[:3], [0.8, 0.2, 0.1], atol=1e-6)
    assert mat.opacity == pytest.approx(0.5)
    assert mat.texture_path.endswith("cube_texture.png")
    assert mesh.uvs is not None
    assert mesh.uvs.shape == (mesh.num_vertices, 2)
    assert mesh.num_vertices > 8  # uv seams split corners; welding by position still closes it


def test_scale_option_converts_millimetres(data_dir):
    mesh = mgn.load_mesh(data_dir / "cube.stl", scale=0.001)
    assert mgn.mass_properties(mesh).volume == pytest.approx(8e-15, rel=1e-5)


def test_mesh_arrays_are_read_only_views_owned_by_the_mesh():
    mesh = mgn.make_box([0.1, 0.2, 0.3])
    v = mesh.vertices
    assert v.dtype == np.float32
    assert v.shape == (8, 3)
    with pytest.raises(ValueError, match="read-only"):
        v[0, 0] = 1.0
    del mesh  # the view keeps the mesh alive
    assert np.ptp(v, axis=0) == pytest.approx([0.1, 0.2, 0.3])


@pytest.mark.parametrize("density", [1.0, 750.0])
def test_box_mass_properties_match_analytic(density, rng):
    a, b, c = 0.08, 0.12, 0.05
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    R *= np.sign(np.linalg.det(R))
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = (0.3, -0.1, 0.2)
    p = mgn.mass_properties(mgn.make_box([a, b, c]).transformed(X), density)
    m = density * a * b * c
    assert p.is_exact
    assert p.mass == pytest.approx(m, rel=1e-5)
    np.testing.assert_allclose(p.center_of_mass, X[:3, 3], atol=1e-6)
    I_body = m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    np.testing.assert_allclose(p.inertia, R @ I_body @ R.T, atol=1e-5 * I_body.max())


def test_cylinder_and_sphere_mass_properties_match_analytic():
    r, h, rho = 0.03, 0.1, 1000.0
    cyl = mgn.mass_properties(mgn.make_cylinder(r, h, segments=720), rho)
    m = rho * np.pi * r * r * h
    assert cyl.mass == pytest.approx(m, rel=1e-4)
    np.testing.assert_allclose(
        np.diag(cyl.inertia), [m * (3 * r * r + h * h) / 12] * 2 + [m * r * r / 2], rtol=2e-4
    )
    sph = mgn.mass_properties(mgn.make_sphere(0.05, 720, 360), rho)
    m = rho * 4 / 3 * np.pi * 0.05**3
    assert sph.mass == pytest.approx(m, rel=2e-4)
    np.testing.assert_allclose(np.diag(sph.inertia), [0.4 * m * 0.05**2] * 3, rtol=5e-4)


def test_flipped_mesh_is_not_outward_but_mass_is_still_positive():
    box = mgn.make_box([0.1, 0.1, 0.1]).flipped()
    r = box.validate()
    assert r.is_watertight
    assert r.is_winding_consistent
    assert not r.is_outward
    assert r.signed_volume == pytest.approx(-1e-3, rel=1e-5)
    assert mgn.mass_properties(box).volume == pytest.approx(1e-3, rel=1e-5)


def test_open_mesh_uses_the_documented_shell_fallback():
    box = mgn.make_box([1.0, 1.0, 1.0])
    open_box = mgn.Mesh(box.vertices, box.faces[:10])
    assert not open_box.validate().is_watertight
    p = mgn.mass_properties(open_box, 1000.0, shell_thickness=0.001)
    assert not p.is_exact
    assert p.mass == pytest.approx(5.0)  # five unit faces, 1 mm thick, 1000 kg/m^3
    with pytest.raises(mgn.InvalidArgumentError, match="not closed"):
        mgn.mass_properties(open_box, open_mesh="error")


@pytest.mark.parametrize("method", ["random", "even"])
def test_samples_lie_on_the_surface_with_outward_normals(method):
    r = 0.04
    sphere = mgn.make_sphere(r, 128, 64)
    s = mgn.sample_surface(sphere, 1000, method=method, seed=5)
    assert len(s) == 1000
    np.testing.assert_allclose(np.linalg.norm(s.points, axis=1), r, rtol=1e-3)
    assert np.all(np.einsum("ij,ij->i", s.points, s.normals) > 0)
    again = mgn.sample_surface(sphere, 1000, method=method, seed=5)
    np.testing.assert_array_equal(s.points, again.points)
    other = mgn.sample_surface(sphere, 1000, method=method, seed=6)
    assert not np.array_equal(s.points, other.points)


def test_random_sampling_is_area_weighted():
    # A 1 x 1 x 0.01 slab: the two big faces hold ~98 % of the area.
    slab = mgn.make_box([1.0, 1.0, 0.01])
    s = mgn.sample_surface(slab, 20000, seed=1)
    on_big_faces = np.isclose(np.abs(s.points[:, 2]), 0.005, atol=1e-6).mean()
    assert on_big_faces == pytest.approx(2.0 / (2.0 + 4 * 0.01), abs=0.01)


def test_even_sampling_spreads_points_further_apart_than_random():
    box = mgn.make_box([0.1, 0.1, 0.1])

    def min_spacing(points):
        d = np.linalg.norm(points[:, None] - points[None], axis=2)
        d[np.diag_indices_from(d)] = np.inf
        return d.min()

    even = mgn.sample_surface(box, 300, method="even").points
    rand = mgn.sample_surface(box, 300, method="random").points
    assert min_spacing(even) > 3 * min_spacing(rand)
