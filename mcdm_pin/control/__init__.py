"""Force distribution in a control loop: computed-torque laws (:mod:`.laws`), the controller with a
deadline and a fallback (:mod:`.controller`), MuJoCo as the plant (:mod:`.plant`), the loop
(:mod:`.loop`), its real-time conditions and per-tick probes (:mod:`.realtime`) and its figure
(:mod:`.plot`). MuJoCo is the
optional ``mjcf`` extra. See docs/control.md."""

from .controller import Controller, Tick
from .laws import JointSpaceLaw, TaskSpaceLaw, pid_gains
from .loop import LoopResult, back_and_forth, reverse, run_loop, sample, scaled_masses, time_scaled, tracking_errors
from .plant import MujocoPlant
from .plot import plot_run
from .realtime import Conditions, Probe, wait_until

__all__ = ["Conditions", "Controller", "JointSpaceLaw", "LoopResult", "MujocoPlant", "Probe", "TaskSpaceLaw",
           "Tick", "back_and_forth", "pid_gains", "plot_run", "reverse", "run_loop", "sample", "scaled_masses", "time_scaled",
           "tracking_errors", "wait_until"]
