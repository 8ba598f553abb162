"""Force distribution in a control loop: computed-torque laws (:mod:`.laws`), the controller with a
deadline and a fallback (:mod:`.controller`), MuJoCo as the plant (:mod:`.plant`) and the loop
(:mod:`.loop`). MuJoCo is the optional ``mjcf`` extra. See docs/control.md."""

from .controller import Controller, Tick
from .laws import JointSpaceLaw, TaskSpaceLaw, pid_gains
from .loop import LoopResult, back_and_forth, reverse, run_loop, sample, scaled_masses, time_scaled, tracking_errors
from .plant import MujocoPlant

__all__ = ["Controller", "JointSpaceLaw", "LoopResult", "MujocoPlant", "TaskSpaceLaw", "Tick", "back_and_forth",
           "pid_gains", "reverse", "run_loop", "sample", "scaled_masses", "time_scaled", "tracking_errors"]
