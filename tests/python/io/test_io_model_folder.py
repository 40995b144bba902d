"""Built-in objects through the C++ core, and the MetaGraspNet object-folder round trip."""

import h5py
import numpy as np
import pytest

import mgn
from mgn.io import read_model_folder, write_model_folder
from mgn.objects import NUM_COM_KEYPOINTS, builtin_objects, get_object


@pytest.mark.parametrize("spec", builtin_objects(), ids=lambda s: s.name)
def test_builtin_object_is_a_valid_solid_in_mgn(spec):
    mesh = spec.to_mesh()
    report = mesh.validate()
    assert report.is_watertight, report
    assert report.is_outward, report
    props = mgn.mass_properties(mesh, spec.density)
    assert props.is_exact
    assert props.volume > 0
    lo, hi = mesh.bounds
    assert np.all(props.center_of_mass > lo)
    assert np.all(props.center_of_mass < hi)
    assert props.mass == pytest.approx(spec.density * props.volume)
    # principal moments of a real body obey the triangle inequality
    moments = np.linalg.eigvalsh(props.inertia)
    assert moments.min() > 0
    assert moments[2] <= moments[0] + moments[1] + 1e-12


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    root = tmp_path_factory.mktemp("export")
    specs = [get_object("box_cereal"), get_object("mug"), get_object("wine_glass")]
    folders = [write_model_folder(s, root) for s in specs]
    return root, specs, folders


def test_folder_layout_and_hdf5_contract(exported):
    root, specs, folders = exported
    for spec, folder in zip(specs, folders, strict=True):
        assert folder == root / "models" / f"{spec.category_id:03d}"
        for name in ("textured.obj", "textured.mtl", "textured.urdf", "textured.obj.hdf5"):
            assert (folder / name).is_file()
        assert (folder / "texture.png").is_file() == (spec.material.texture is not None)
        with h5py.File(folder / "textured.obj.hdf5") as h5:
            assert h5["keypts/byhand"].shape == (len(spec.keypoints), 4)
            assert h5["keypts/com"].shape == (NUM_COM_KEYPOINTS, 4)
            assert h5["grasps/paralleljaw/pregrasp_transform"].shape == (0, 10)
            assert h5["grasps/suctioncup/pregrasp_transform"].shape == (0, 6)
            for ds in ("keypts/byhand", "keypts/com", "grasps/paralleljaw/quality_score"):
                assert h5[ds].dtype == np.float32
            # centimetres: the by-hand keypoints are the spec's metres x 100
            np.testing.assert_allclose(
                h5["keypts/byhand"][:, 1:],
                [np.array(k.position) * 100 for k in spec.keypoints],
                rtol=1e-6,
                atol=1e-5,
            )
    assert not list(root.glob("models/.*")), "no temporary folders may be left behind"


def test_round_trip_keeps_geometry_material_and_mass(exported):
    _, specs, folders = exported
    for spec, folder in zip(specs, folders, strict=True):
        mf = read_model_folder(folder)
        original = spec.to_mesh()
        assert mf.mesh.validate().is_outward
        v0 = mgn.mass_properties(original, spec.density)
        v1 = mgn.mass_properties(mf.mesh, spec.density)
        assert v1.volume == pytest.approx(v0.volume, rel=1e-5)
        np.testing.assert_allclose(v1.center_of_mass, v0.center_of_mass, atol=1e-6)
        assert mf.metadata["name"] == spec.name
        assert mf.metadata["mass_kg"] == pytest.approx(v0.mass)
        (mat,) = mf.mesh.materials
        assert mat.opacity == pytest.approx(spec.material.opacity, abs=1e-6)
        if spec.material.texture is not None:
            assert mat.texture_path.endswith("texture.png")
            assert mf.mesh.uvs is not None


def test_com_keypoint_scores_follow_distance_to_the_centre_of_mass(exported):
    _, _specs, folders = exported
    mf = read_model_folder(folders[0])
    com = np.array(mf.metadata["center_of_mass_m"])
    score, pts = mf.keypoints_com[:, 0], mf.keypoints_com[:, 1:]
    d = np.linalg.norm(pts - com, axis=1)
    assert score.min() == pytest.approx(0.0, abs=1e-6)
    assert score.max() == pytest.approx(1.0)
    np.testing.assert_allclose(score, (d.max() - d) / (d.max() - d.min()), atol=1e-5)


def test_export_refuses_to_overwrite_unless_asked(exported):
    root, specs, folders = exported
    with pytest.raises(mgn.IoError, match="already exists"):
        write_model_folder(specs[0], root)
    assert write_model_folder(specs[0], root, overwrite=True) == folders[0]
