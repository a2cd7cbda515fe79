"""The ament_python layout: installed the way colcon builds it, every executable resolves as `ros2 run` does."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ament_index_python = pytest.importorskip("ament_index_python", reason="needs the project venv (make test)")

ROOT = Path(__file__).resolve().parents[2]
NODE_EXECUTABLES = ("planner", "sim", "ejector", "safety_monitor", "radar", "radar_od", "ic_planner", "recorder",
                    "analysis_server")


@pytest.fixture(scope="module")
def install_prefix(tmp_path_factory):
    """`colcon build` of an ament_python package runs setup.py egg_info/build/install into the install prefix."""
    base = tmp_path_factory.mktemp("colcon")
    (base / "build").mkdir()
    prefix = base / "install" / "roe_sep"
    subprocess.run(
        [sys.executable, "setup.py", "-q", "egg_info", "--egg-base", str(base / "build"), "build", "--build-base",
         str(base / "build"), "install", "--prefix", str(prefix), "--record", str(base / "install.log"),
         "--single-version-externally-managed"],
        cwd=ROOT, check=True, capture_output=True)
    return prefix


def resolve(prefix, package, executable):
    """ros2run's lookup: the package prefix from the ament index, then <prefix>/lib/<package>/<executable>."""
    env_before = os.environ.get("AMENT_PREFIX_PATH")
    os.environ["AMENT_PREFIX_PATH"] = str(prefix) + (os.pathsep + env_before if env_before else "")
    try:
        found = Path(ament_index_python.get_package_prefix(package))
    finally:
        if env_before is None:
            del os.environ["AMENT_PREFIX_PATH"]
        else:
            os.environ["AMENT_PREFIX_PATH"] = env_before
    return found / "lib" / package / executable


def test_every_node_resolves_like_ros2_run(install_prefix):
    for exe in (*NODE_EXECUTABLES, "roe-sep"):
        path = resolve(install_prefix, "roe_sep", exe)
        assert path.is_file() and os.access(path, os.X_OK), path
        assert path.parent.parent.parent == install_prefix
    assert (install_prefix / "share" / "roe_sep" / "package.xml").is_file()
    assert (install_prefix / "share" / "roe_sep" / "config" / "default.yaml").is_file()


@pytest.mark.dds
def test_installed_executables_run_the_installed_code(install_prefix):
    site = next((install_prefix / "lib").glob("python3*/site-packages"))
    env = dict(os.environ, PYTHONPATH=str(site), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    where = subprocess.run([sys.executable, "-c", "import roe_sep; print(roe_sep.__file__)"], env=env,
                           capture_output=True, text=True, cwd=install_prefix).stdout
    assert Path(where.strip()).is_relative_to(install_prefix)
    planner = resolve(install_prefix, "roe_sep", "planner")
    proc = subprocess.run([str(planner), "--ros-args", "-p", "k:=2"], env=env, capture_output=True, text=True,
                          timeout=60, cwd=install_prefix)
    assert proc.returncode == 2 and "'k'" in proc.stderr + proc.stdout
    cli = resolve(install_prefix, "roe_sep", "roe-sep")
    proc = subprocess.run([str(cli), "design", "--json"], env=env, capture_output=True, text=True, timeout=60,
                          cwd=install_prefix)
    assert proc.returncode == 0 and '"dv1_rtn"' in proc.stdout
