"""The end of a window (a part of :mod:`.model`): where the robots stand at its last time point.

A window of a schedule re-solved with ``end`` (a :class:`~bille.instances.State`) must end in
that state, so that the rest of the schedule fits after it. With ``swap``, robots that are
interchangeable (one moveset graph, no goal cell) may end in one another's end states instead:
the robots of a group must then cover the group's end poses, one each, with the load that goes
with the pose. A solution that ends robot ``i`` in robot ``j``'s end state fits too, once the
rest of the schedule is permuted: robot ``i`` goes on with ``j``'s actions, which are ids of the
same moveset graph and start from the same pose and load (:func:`roles_taken`). No schedule of
the window is lost; schedules that swap roles are gained.
"""
from __future__ import annotations

from bille.instances import Instance


def end_roles(instance: Instance, swap: bool) -> list[tuple[int, ...]]:
    """Per robot, the robots whose end state it may take: itself, or with ``swap`` every robot of
    its moveset graph without a goal cell (robots with a goal cell keep their own)."""
    m = instance.num_robots
    if not swap:
        return [(i,) for i in range(m)]
    graphs, goals = instance.world.graphs, instance.goal_cells
    return [tuple(j for j in range(m) if graphs[j] is graphs[i] and goals[j] < 0) if goals[i] < 0 else (i,)
            for i in range(m)]


def end_poses(end, roles: tuple[int, ...]) -> list[int]:
    return [end.poses[j] for j in roles]


def add_end_constraints(builder) -> None:
    """Every end pose of a group is taken by one of its robots, with that pose's load; record the
    literals for :func:`roles_taken`."""
    m, end, T = builder.m, builder.end, builder.T
    for i, roles in enumerate(builder.roles):
        for j in roles:
            x = builder.x.get((i, T, end.poses[j]))
            if x is None:
                continue
            m.ends.setdefault(i, []).append((j, x))
            if len(roles) > 1:
                load = builder.carry[(i, T)]
                m.clauses.append([-x, load if end.carrying[j] else -load])
    for i, roles in enumerate(builder.roles):
        if len(roles) > 1 and i == min(roles):  # one clause per group and end pose
            for j in roles:
                m.clauses.append([x for k in roles for r, x in m.ends.get(k, []) if r == j])


def roles_taken(model, value, m: int) -> list[int]:
    """Per robot ``i`` of ``m``, the robot ``j`` whose end state it reached in a solution
    (itself without ``swap``)."""
    out = list(range(m))
    for i, options in model.ends.items():
        for j, x in options:
            if value(x):
                out[i] = j
    return out
