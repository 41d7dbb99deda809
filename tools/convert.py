"""``bille convert``: instances and schedules to and from MovingAI and libMultiRobotPlanning."""
from __future__ import annotations

from pathlib import Path

import click

from bille.instances import InstanceError, ScheduleError, dump_instance, load_instance
from bille.instances.files import write_atomic
from bille.instances.interop import (from_mrp, is_mrp, map_text, scen_text, schedule_from_mrp,
                                     schedule_to_mrp, to_mrp)
from bille.instances.schedule import dump_schedule, load_schedule, written_for
from bille.instances.yamlsource import load_yaml_file, mrp_name

from .common import EXIT_OK, instance_arg, writable


def _yaml(data) -> str:
    import yaml

    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None)


@click.command()
@click.argument("source")
@click.argument("target")
@click.option("--instance", "instance_path", metavar="INSTANCE",
              help="For a schedule: the instance it belongs to (a bundled name, or a file in any format "
                   "convert reads: .yaml, .mrp.yaml, .scen with its .map).")
@click.option("--agents", type=click.IntRange(min=1), help="From a .scen: its first N usable rows (default: all).")
@click.option("--map", "map_path", type=click.Path(dir_okay=False),
              help="From a .scen: the .map file (default: the one the scenario names, in its folder).")
def convert(source: str, target: str, instance_path: str | None, agents: int | None, map_path: str | None) -> int:
    """Convert SOURCE to TARGET, formats told by the file names: bille YAML (.yaml),
    libMultiRobotPlanning YAML (*.mrp.yaml), MovingAI (.scen with its .map; a .map alone holds no
    agents). Instances go both ways; schedules between bille and libMultiRobotPlanning, with
    --instance. Formats of point robots on a fixed grid cannot hold two-footed robots or tiles that
    move: that is one clear error."""
    writable(target)
    kind, value = _read(source, instance_path, agents, map_path)
    if kind == "instance":
        _write_instance(value, target)
    else:
        if not mrp_name(target) and not target.endswith((".yaml", ".yml")):
            raise ScheduleError(f"{target}: a schedule is written as .yaml (bille) or .mrp.yaml (libMultiRobotPlanning)")
        inst = _instance(instance_path)
        text = _yaml(schedule_to_mrp(inst, value)) if mrp_name(target) else dump_schedule(value)
        write_atomic(target, text, ScheduleError)
        if (value.meta or {}).get("agents"):
            click.echo(f"{source}: agents {value.meta['agents']}")
    click.echo(f"{source} -> {target}")
    return EXIT_OK


def _instance(path: str, agents: int | None = None, map_path: str | None = None):
    """An instance from a file in any format convert reads, or a bundled name."""
    kind, inst = _read(path, None, agents, map_path, schedules=False)
    return inst


def _read(source: str, instance_path, agents, map_path, schedules: bool = True):
    path = Path(source)
    if path.suffix == ".scen":
        from bille.instances.generators.movingai import from_movingai, scen_map

        mp = Path(map_path) if map_path else scen_map(path)
        return "instance", from_movingai(mp, path, agents=agents, name=path.stem)
    if path.suffix == ".map":
        raise InstanceError(f"{source}: a .map holds no agents; convert its .scen (with --map if needed)")
    if not path.is_file():
        return "instance", instance_arg(source)  # a bundled name
    data, src = load_yaml_file(path, InstanceError)
    if is_mrp(data):
        return "instance", from_mrp(data, path.name.split(".")[0], src)
    if isinstance(data, dict) and "grid" in data:
        return "instance", load_instance(path)
    if not schedules:
        raise InstanceError(f"{source}: not an instance (expected bille YAML with a grid, libMultiRobotPlanning "
                            "YAML with map and agents, or a MovingAI .scen)")
    if instance_path is None:
        raise ScheduleError(f"{source}: " + ("a libMultiRobotPlanning schedule needs --instance"
                                             if isinstance(data, dict) and "schedule" in data
                                             else "neither an instance nor a schedule with --instance"))
    inst = _instance(instance_path)
    if isinstance(data, dict) and "schedule" in data:
        src.error = ScheduleError
        return "schedule", schedule_from_mrp(inst, data, src)
    schedule = load_schedule(path)
    why = written_for(inst, schedule)
    if why is not None:
        click.echo(f"warning: {why}", err=True)
    return "schedule", schedule


def _write_instance(inst, target: str) -> None:
    path = Path(target)
    if path.suffix == ".scen":  # both texts first: nothing is written if either cannot be
        map_file = path.with_suffix(".map")
        writable(map_file)
        texts = {map_file: map_text(inst), path: scen_text(inst, map_file.name)}
        for file, text in texts.items():
            write_atomic(file, text, InstanceError)
        click.echo(f"map written to {map_file}")
    elif path.suffix == ".map":
        write_atomic(path, map_text(inst), InstanceError)
    elif mrp_name(path):
        write_atomic(path, _yaml(to_mrp(inst)), InstanceError)
    elif path.suffix in (".yaml", ".yml"):
        write_atomic(path, dump_instance(inst), InstanceError)
    else:
        raise InstanceError(f"{target}: unknown format (expected .yaml, .mrp.yaml, .scen or .map)")
