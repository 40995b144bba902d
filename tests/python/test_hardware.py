"""Default gripper and suction cup: MetaGraspNet values, validation, YAML round trip."""

import pytest

import mgn
from mgn.hardware import ParallelJawGripper, SuctionCup, default_cup, default_gripper


def test_defaults_are_the_metagraspnet_values():
    g = default_gripper()
    assert g.max_opening == pytest.approx(0.080)
    assert g.flange_to_contact == pytest.approx(0.1041)
    assert g.collision_opening(0.02) == pytest.approx(0.05)
    assert g.collision_opening(0.07) == pytest.approx(0.08)
    c = default_cup()
    assert (c.radius, c.num_points, c.c1, c.c2) == (0.007, 128, 0.03768, 0.06241)
    assert c.pressure_difference == pytest.approx(0.7)


def test_yaml_round_trip(tmp_path):
    g = ParallelJawGripper(name="wide", max_opening=0.12, finger_size=(0.01, 0.03, 0.06))
    path = tmp_path / "g.yaml"
    g.to_yaml(path)
    assert ParallelJawGripper.from_yaml(path) == g
    c = SuctionCup(name="flat_30mm", radius=0.015, outer_radius=0.016)
    c.to_yaml(tmp_path / "c.yaml")
    assert SuctionCup.from_yaml(tmp_path / "c.yaml") == c


def test_bad_hardware_is_rejected_with_the_field_named(tmp_path):
    with pytest.raises(mgn.InvalidArgumentError, match="max_opening"):
        ParallelJawGripper(max_opening=-0.01)
    with pytest.raises(mgn.InvalidArgumentError, match="num_points"):
        SuctionCup(num_points=3)
    with pytest.raises(mgn.InvalidArgumentError, match="outer_radius"):
        SuctionCup(radius=0.02, outer_radius=0.01)
    (tmp_path / "x.yaml").write_text("radius: 0.01\nlip_colour: red\n")
    with pytest.raises(mgn.InvalidArgumentError, match="lip_colour"):
        SuctionCup.from_yaml(tmp_path / "x.yaml")
    with pytest.raises(mgn.IoError, match=r"nope.yaml"):
        SuctionCup.from_yaml(tmp_path / "nope.yaml")
