"""Recovery after a fault: bring the robots back to a known step, and plan the rest again from
the state they report (``--on-fault retry`` and ``replan``; docs/execution.md)."""
from __future__ import annotations

import logging

import numpy as np

from bille.instances import instance_at
from bille.instances.rules import Violation, apply
from bille.solvers import Schedule, bind, save_schedule, solve

from .journal import plan_states, sha256_file
from .outcome import Fault
from .protocol import ExecutionError

log = logging.getLogger("bille.execute")


class Recovery:
    """The executor's fault handling (a part of :class:`.executor.Executor`)."""

    def recover(self, k: int, fault: Fault) -> int | None:
        """Bring the robots back to the state after step ``k - 1`` and (for ``replan``) plan again.

        Returns the step to release next, or None when the run must stop.
        """
        self.connection = {r: s for r, s in self.connection.items() if s == "ONLINE"}
        self.reports = {r: rep for r, rep in self.reports.items() if r != fault.robot}
        try:
            self.bring_up(k - 1, k, self.s.reconnect_timeout)
        except ExecutionError as exc:
            log.warning("recovery of step %d failed: %s", k, exc)
            return None
        return self.replan_at(k) if self.s.on_fault == "replan" else k

    def replan_at(self, k: int) -> int | None:
        """Re-plan before releasing step ``k`` (robots at step ``k - 1``, some perhaps at ``k``);
        the step to release next, or None."""
        robots = self.s.robots
        done = [i for i, r in enumerate(robots) if self.reports[r]["lastStep"] == k]
        if not self.replan(k, done):
            return None
        if not done:
            return k
        # the robots' copies of the world took in the whole step: give them the world as it is
        self.request_state(robots, self.initialize_params(k), kind="initialize")
        if self.wait_for(robots, lambda rep: rep["lastStep"] == k and self.matches(robots.index(rep["robot"]), rep, k),
                         self.s.step_timeout):
            return None
        self.journal.write("finished", step=k)
        return k + 1

    def replan(self, k: int, done: list[int]) -> bool:
        """Plan from the state the robots report, with the chosen method.

        If robots ``done`` finished step ``k`` and the others did not, step ``k`` becomes what
        happened (the others wait) and the plan goes on after it; otherwise after step ``k - 1``.
        """
        inst, prefix = self.instance, self.plan[:, : k - 1]
        st = self.states[k - 1]
        if done:
            for r in self.s.robots:
                self.reports.pop(r, None)
            step = np.array([self.plan[i, k - 1] if i in done else inst.movesets[i].wait for i in range(inst.num_robots)])
            st = apply(self.world, st, step, step=k)
            if isinstance(st, Violation):
                log.warning("cannot re-plan: step %d done by only some robots breaks the rules: %s", k, st.message)
                return False
            prefix = np.concatenate([prefix, step[:, None]], axis=1)
        result = solve(instance_at(inst, st, f"{inst.name}-from-{prefix.shape[1]}"), self.s.replan_method,
                       time_limit=self.s.replan_time_limit)
        if result.schedule is None or result.status not in ("optimal", "feasible"):
            log.warning("re-planning from step %d with %s found no schedule (%s)", prefix.shape[1],
                        self.s.replan_method, result.status)
            return False
        tail = np.concatenate([prefix[:, k - 1:], bind(inst, result.schedule)], axis=1)
        path = self.journal.path.with_name(f"{self.journal.path.name}.replan-{k - 1}.schedule.yaml")
        save_schedule(Schedule.from_ids(inst, tail), path)
        plan = np.concatenate([self.plan[:, : k - 1], tail], axis=1)
        self.set_plan(plan, self.states[:k] + plan_states(inst, tail, "the re-planned schedule", self.states[k - 1])[1:])
        self.journal.write("replan", step=k - 1, schedule=str(path), schedule_sha256=sha256_file(path),
                           method=self.s.replan_method, steps=int(tail.shape[1]))
        return True
