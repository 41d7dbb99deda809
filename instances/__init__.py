"""The problem: the grid world, movesets, pose graphs, the rules, instances and their files."""
from .errors import BilleError, InstanceError, MovesetError, OptionError, ScheduleError
from .grid import Grid, articulation_points, is_connected, may_pick
from .instance import (
    Instance,
    Robot,
    Task,
    check_instance,
    instance_at,
    instance_from_text,
    load_instance,
)
from .moveset import Action, Kind, Moveset, load_moveset
from .posegraph import PoseGraph, compile_posegraph
from .rules import RULES, State, Violation, World, apply, goal_violation
from .writing import dump_instance, save_instance

__all__ = [
    "Action", "BilleError", "Grid", "Instance", "InstanceError", "Kind", "Moveset", "MovesetError",
    "OptionError", "PoseGraph", "RULES", "Robot", "ScheduleError", "State", "Task", "Violation",
    "World", "apply", "articulation_points", "check_instance", "compile_posegraph", "dump_instance",
    "goal_violation", "instance_at", "instance_from_text", "is_connected", "load_instance", "load_moveset",
    "may_pick", "save_instance",
]
