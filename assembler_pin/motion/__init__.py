"""Motion of the stack: EE paths, force-optimal plans along them, and their time law.

* :mod:`.paths` — EE paths through waypoints (screw or linear interpolation).
* :mod:`.planner` — :func:`plan_path`: valid, force-optimized, continuous samples.
* :mod:`.timing` — :func:`time_parametrize`: leg-length trajectories within the legs'
  speed and acceleration limits; :func:`plan_trajectory`: plan, time and check.
* :mod:`.trajfile` — trajectory files (CSV/JSON): atomic writer, strict reader.
* :mod:`.rows` — every row of a trajectory held to the model (stack FK of its lengths).
"""

from ..config.choices import PATH_KINDS
from ..exceptions import PathError
from .paths import EEPath, interpolate_pose, read_waypoints
from .planner import PlanOptions, PlanResult, plan_path

__all__ = [
    "PATH_KINDS",
    "EEPath",
    "PathError",
    "PlanOptions",
    "PlanResult",
    "interpolate_pose",
    "plan_path",
    "read_waypoints",
]
