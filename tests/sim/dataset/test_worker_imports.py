"""What a dataset process loads: the scenario schema and the dataset driver pull in no
navigation filter, estimation roles, scipy.stats or target meshes (the parent of a multi-worker
run, and each worker where they are spawned, pay their imports); what a scene job imports
builds meshes and looks up depths with numpy (no trimesh, no scipy.interpolate or
scipy.spatial, about 0.4 s of CPU a process); the lazy package exports still resolve."""

from __future__ import annotations

import importlib
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
LAZY_PACKAGES = ("autonomy.atr", "autonomy.estimation", "autonomy.localization", "autonomy.navigation",
                 "autonomy.tracking", "autonomy.world_model", "scenarios")


def test_dataset_driver_and_schema_load_no_navigation_estimation_or_meshes():
    code = ("import sys, sim.dataset.generate, scenarios.schema, scenarios.config.fls\n"
            "print(' '.join(sorted(sys.modules)))")
    loaded = set(subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                                check=True).stdout.split())
    assert "scenarios.schema" in loaded and "autonomy.navigation.config" in loaded  # the probe ran
    unused = {"autonomy.navigation.ekf", "autonomy.estimation.gater", "autonomy.atr.classical",
              "autonomy.world_model.pmha", "scenarios.load", "scipy.stats", "trimesh", "sim.scene.target_meshes"}
    assert not unused & loaded


def test_scene_job_modules_load_no_trimesh_or_scipy_interpolation():
    code = ("import importlib, sys, sim.dataset.generate as g\n"
            "for name in g.worker_modules(g.RenderSettings()) + g.worker_modules(g.SssSettings()):\n"
            "    importlib.import_module(name)\n"
            "print(' '.join(sorted(sys.modules)))")
    loaded = set(subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                                check=True).stdout.split())
    assert {"sim.scene.world", "sim.scene.target_meshes", "sim.sensors.fls", "sim.sensors.sss"} <= loaded  # the probe ran
    assert not {"trimesh", "scipy.interpolate", "scipy.spatial"} & loaded


@pytest.mark.parametrize("package", LAZY_PACKAGES)
def test_every_exported_name_resolves(package):
    mod = importlib.import_module(package)
    assert mod.__all__
    for name in mod.__all__:
        assert getattr(mod, name) is not None
    with pytest.raises(AttributeError):
        getattr(mod, "no_such_name")
