"""The analysis_server node as a real process over DDS: both services, bad requests answered, bad parameters."""

import math

import pytest
from roe_sep_msgs.srv import ClusterProgram, DeploymentAssessment  # noqa: E402
from rosutil import rclpy, spin_until, start_node, stop_node, wait_exit  # noqa: I001  (skips without rclpy)

from roe_sep.nodes.analysis_server import CLUSTER_SERVICE, DEPLOYMENT_SERVICE  # noqa: E402

pytestmark = pytest.mark.dds  # every test here starts a node or an rclpy context


@pytest.fixture()
def ground(ros_context):
    node = rclpy.create_node("analysis_test")
    yield node
    node.destroy_node()


def _call(node, client, req, timeout=60.0):
    future = client.call_async(req)
    assert spin_until(node, future.done, timeout=timeout)
    return future.result()


def test_services(ground, tmp_path):
    small = tmp_path / "cluster.yaml"
    small.write_text("max_delay: 50.0\n")
    server = start_node("analysis_server", "-p", f"cluster_file:={small}")
    try:
        dep = ground.create_client(DeploymentAssessment, DEPLOYMENT_SERVICE)
        clu = ground.create_client(ClusterProgram, CLUSTER_SERVICE)
        assert dep.wait_for_service(timeout_sec=20) and clu.wait_for_service(timeout_sec=20)
        incl = math.radians(97.03)
        radial = _call(ground, dep, DeploymentAssessment.Request(inclination=incl, dv=1.0, angle=math.pi / 2))
        vbar = _call(ground, dep, DeploymentAssessment.Request(inclination=incl, dv=1.0, angle=math.pi))
        assert radial.success and vbar.success, (radial.message, vbar.message)
        assert radial.min_distance_first_orbit < 50.0 < 1000.0 < vbar.min_distance_first_orbit
        assert vbar.distance_end > radial.distance_end
        assert len(radial.times) == len(radial.distances) and radial.times[-1] == pytest.approx(10 * 86400)
        bad = _call(ground, dep, DeploymentAssessment.Request(inclination=incl, dv=-1.0))
        assert not bad.success and "dv" in bad.message
        high = _call(ground, dep, DeploymentAssessment.Request(altitude=1500e3, inclination=incl, dv=1.0))
        assert not high.success and "1100 km" in high.message
        equatorial = _call(ground, dep, DeploymentAssessment.Request(inclination=0.0, dv=1.0))
        assert not equatorial.success and equatorial.message.endswith("got [0.0]"), equatorial.message  # no NumPy

        prog = _call(ground, clu, ClusterProgram.Request(samples=500))
        assert prog.success, prog.message
        assert len(prog.delays) == 4 and prog.velocities == pytest.approx([2.0, 2.0, 2.0, 1.0])
        assert min(prog.delays[:3]) == 5.0 and 0.0 < prog.max_pair_distance <= 10000.0
        assert 0.0 < prog.p_safe <= 1.0
        bad = _call(ground, clu, ClusterProgram.Request(velocities=[2.0, 2.0]))
        assert not bad.success and "delta_q" in bad.message
        assert server.poll() is None
    finally:
        code, out = stop_node(server)
    assert code == 0, out


def test_bad_parameter_refused_at_startup():
    code, out = wait_exit(start_node("analysis_server", "-p", "cluster_file:=/nonexistent.yaml"))
    assert code == 2, out
    assert "'cluster_file'" in out
    code, out = wait_exit(start_node("analysis_server", "-p", "deploy_model:=gmat"))
    assert code == 2, out
    assert "'deploy_model'" in out
