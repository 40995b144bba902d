"""The facade ``mgn`` names what the product is: the dataset pipeline and the scene, besides the
geometry, and imports the pipeline only when it is used."""

from __future__ import annotations

import subprocess
import sys

import mgn
import mgn.io.dataset
import mgn.pipeline
import mgn.pipeline.config
import mgn.scene

PRODUCT = ("generate", "GenerateReport", "Config", "load_config", "Scene", "drop_scene", "Dataset")


def test_the_product_is_in_the_facade() -> None:
    for name in PRODUCT:
        assert name in mgn.__all__, name
        assert name in dir(mgn), name
    assert mgn.generate is mgn.pipeline.generate
    assert mgn.Config is mgn.pipeline.config.Config
    assert mgn.load_config is mgn.pipeline.config.load_config
    assert mgn.Scene is mgn.scene.Scene
    assert mgn.drop_scene is mgn.scene.drop_scene
    assert mgn.Dataset is mgn.io.dataset.Dataset
    assert isinstance(mgn.load_config(None), mgn.Config)


def test_every_name_of_all_resolves() -> None:
    for name in mgn.__all__:
        assert getattr(mgn, name) is not None, name


def test_import_mgn_does_not_import_the_pipeline() -> None:
    code = (
        "import sys, mgn; "
        "print(any(m.startswith(('mgn.pipeline', 'mgn.scene.drop')) for m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.strip() == "False"
