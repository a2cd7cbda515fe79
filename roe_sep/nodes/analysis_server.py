"""analysis_server: deployment assessment (seed 003) and cluster separation program (seed 004) as ROS 2 services.

Services:

* ``/analysis/deployment`` (roe_sep_msgs/srv/DeploymentAssessment): one in-plane deployment of a CubeSat from its
  mother craft, distance vs time over N days (numerical J2-J4 + drag, or the secular ROE model), first-orbit
  closest approach.
  Physics: :mod:`roe_sep.core.deployment.sweep`.
* ``/analysis/cluster_program`` (roe_sep_msgs/srv/ClusterProgram): delays of a nanosatellite group separated from a
  tumbling platform, minimax over the feasible regions, optional statistical check. Physics:
  :mod:`roe_sep.core.deployment.cluster`.

Parameters: :data:`roe_sep.nodes.parameters.ANALYSIS_SERVER` (``analysis_server --help``, docs/parameters.md);
``deploy_density``, ``deploy_step`` and ``deploy_model`` can be changed while it runs (``ros2 param set``), within
their range and choices, and the next request uses them.

A bad request is answered with ``success = false`` and the reason; the node keeps serving.
"""

import dataclasses
import math

from rclpy.node import Node
from roe_sep_msgs.srv import ClusterProgram, DeploymentAssessment

from ..core.config import ConfigError
from ..core.deployment.cluster import Nanosatellite, draw, load_cluster_config, select_program, simulate_program
from ..core.deployment.sweep import DeploymentConfig, sweep
from .params import ParameterError, declare, finite

DEPLOYMENT_SERVICE = "/analysis/deployment"
CLUSTER_SERVICE = "/analysis/cluster_program"
MAX_SAMPLES = 200_000


class AnalysisServer(Node):
    def __init__(self):
        super().__init__("analysis_server")
        cluster_file = declare(self, "cluster_file")
        self.density = declare(self, "deploy_density", attr="density")
        self.step = declare(self, "deploy_step", attr="step")
        self.model = declare(self, "deploy_model", attr="model")
        try:
            self.cluster = load_cluster_config(cluster_file or None)
        except ConfigError as exc:
            raise ParameterError(f"parameter 'cluster_file': {exc}") from exc
        self.create_service(DeploymentAssessment, DEPLOYMENT_SERVICE, self.on_deployment)
        self.create_service(ClusterProgram, CLUSTER_SERVICE, self.on_cluster)
        self.get_logger().info(f"serving {DEPLOYMENT_SERVICE} and {CLUSTER_SERVICE}")

    def on_deployment(self, req, res):
        try:
            if not all(finite(x) for x in (req.altitude, req.inclination, req.dv, req.angle, req.days, req.density)):
                raise ValueError("every request field must be finite")
            cfg = DeploymentConfig(
                altitude=req.altitude or DeploymentConfig.altitude,
                inclinations_deg=(math.degrees(req.inclination),), dv=(req.dv,),
                angles_deg=(math.degrees(req.angle),), days=req.days or DeploymentConfig.days,
                density=self.density if req.density == 0 else max(req.density, 0.0), drag=req.density >= 0,
                step=self.step, model=self.model)
            r = sweep(cfg)
            res.min_distance_first_orbit = float(r.min_first_orbit[0, 0, 0])
            res.time_min_first_orbit = float(r.t_min_first_orbit[0, 0, 0])
            res.distance_end = float(r.distance_end[0, 0, 0])
            res.max_distance = float(r.distance[0, 0, 0].max())
            res.times = r.times.tolist()
            res.distances = r.distance[0, 0, 0].tolist()
            res.success, res.message = True, "ok"
        except ValueError as exc:
            res.success, res.message = False, str(exc)
            self.get_logger().warning(f"deployment request rejected: {exc}")
        return res

    def on_cluster(self, req, res):
        try:
            cfg = self.cluster
            n = len(cfg.sats)
            for name, values in (("velocities", req.velocities), ("delta_q", req.delta_q), ("cluster", req.cluster)):
                if len(values) not in (0, n) and not (len(values) and name == "velocities"):
                    raise ValueError(f"{name}: expected {n} values (or none), got {len(values)}")
            m = len(req.velocities) or n
            if len(req.delta_q) not in (0, m) or len(req.cluster) not in (0, m):
                raise ValueError(f"velocities, delta_q and cluster must have the same length, got "
                                 f"{len(req.velocities)}, {len(req.delta_q)}, {len(req.cluster)}")
            if m != n and not len(req.delta_q):
                raise ValueError(f"delta_q is required when the number of nanosatellites ({m}) differs from the "
                                 f"configuration ({n})")
            sats = []
            for k in range(m):
                base = cfg.sats[k] if k < n else Nanosatellite(f"ns{k + 1}", 1.0, 0.0)
                sats.append(Nanosatellite(base.name, float(req.velocities[k]) if len(req.velocities) else base.velocity,
                                          float(req.delta_q[k]) if len(req.delta_q) else base.delta_q,
                                          bool(req.cluster[k]) if len(req.cluster) else base.cluster))
            changes = {"sats": tuple(sats)}
            if req.sigma:
                changes["sigma_deg_s"] = math.degrees(req.sigma)
            if req.p_required:
                changes["p_required"] = req.p_required
            if req.samples > MAX_SAMPLES:
                raise ValueError(f"samples must be <= {MAX_SAMPLES}, got {req.samples}")
            cfg = dataclasses.replace(cfg, **changes).validate()
            prog = select_program(cfg)
            res.delays = [float(d) for d in prog.delays]
            res.velocities = [s.velocity for s in cfg.sats]
            res.max_pair_distance = float(prog.max_pair_distance)
            res.platform_delay_max = [float(d) for d in prog.platform_delay_max]
            res.p_safe = -1.0
            if prog.feasible and req.samples:
                res.p_safe = simulate_program(cfg, prog.delays, draw(cfg, req.samples, 0))["p_safe"]
            res.success = bool(prog.feasible)
            res.message = "ok" if prog.feasible else "no feasible program on the delay grid"
        except ValueError as exc:
            res.success, res.message = False, str(exc)
            self.get_logger().warning(f"cluster request rejected: {exc}")
        return res


def main(args=None):
    from .spin import run

    return run(AnalysisServer, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
