"""``python3 -m ldcbf_fullbody run SCENARIO [--set KEY=VALUE ...] --out DIR``
(and ``batch``): the command line."""

import argparse
import dataclasses
import pathlib
import sys
from typing import Any, Dict, List, Optional, Tuple

from . import robot, sim


def parse_value(text: str) -> Any:
    """``--set`` values: true/false, an integer, a float, else the string."""
    low = text.strip().lower()
    if low in ("true", "false"):
        return low == "true"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def split_sets(pairs: List[str]) -> Tuple[Dict[str, Any], Dict[str, Any]]:
    """``KEY=VALUE`` strings split into the run's options (``sim.Options``
    fields) and the scenario's overrides (everything else, checked by
    ``ldcbf_nav.load_scenario``)."""
    option_names = {f.name for f in dataclasses.fields(sim.Options)}
    options: Dict[str, Any] = {}
    scenario: Dict[str, Any] = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise ValueError(f"--set {pair!r}: expected KEY=VALUE")
        (options if key in option_names else scenario)[key] = parse_value(value)
    return options, scenario


def controller_config(scenario: Dict[str, Any], sets: Dict[str, Any]) -> Dict[str, Any]:
    """The scenario's controller settings with the robot's geometry and gait
    limits taken from the G1 (``robot.derived_config``); a ``--set`` of a
    controller setting (``delta=0.05``) wins over both."""
    import ldcbf_nav

    config = dict(scenario["config"])
    config.update(robot.derived_config())
    for key, value in sets.items():
        if key in ldcbf_nav.CONFIG_FIELDS:
            config[key] = value
    return config


def run_one(name: str, pairs: List[str], out: pathlib.Path, seed: Optional[int], quiet: bool) -> Dict[str, Any]:
    """One run: loads, walks, writes ``out``; returns the summary."""
    import ldcbf_nav

    from . import report

    option_sets, scenario_sets = split_sets(pairs)
    scenario = ldcbf_nav.load_scenario(name, seed=seed, **scenario_sets)
    if scenario["perception"] != "known":
        raise ValueError(
            f"{name}: perception {scenario['perception']!r}: "
            "the full-body loop runs the controller on the known map"
        )
    options = sim.Options(**option_sets)
    config = controller_config(scenario, scenario_sets)
    subgoals = planned_subgoals(name, pairs, seed) if scenario["planner"] != "none" else None
    result = sim.run(scenario, config, options, log=None if quiet else print, subgoals=subgoals)
    report.write(result, out, config)
    return result["summary"]


#: Settings of the derived configuration that the scenario file keeps under
#: ``[robot]`` rather than ``[controller]``.
ROBOT_FIELDS = ("body_radius", "foot_length", "foot_width")


def lip_overrides(pairs: List[str]) -> Dict[str, Any]:
    """The ``--set`` overrides that make ``ldcbf-sim run`` (the LIP plant) use
    the full-body run's robot: the G1's derived settings, then the user's."""
    option_sets, scenario_sets = split_sets(pairs)
    sets: Dict[str, Any] = {}
    for key, value in robot.derived_config().items():
        sets[f"robot.{key}" if key in ROBOT_FIELDS else key] = value
    sets.update(scenario_sets)
    return sets


def planned_subgoals(name: str, pairs: List[str], seed: Optional[int]) -> List[List[float]]:
    """The global planner's subgoals (W, m; the last one the goal) for a
    scenario with a planner on the known map. ``ldcbf_nav`` exposes the
    planner only inside its closed loop: the LIP plant's run with the G1's
    settings (:func:`run_lip`'s) is made and its ``subgoals`` kept, the plan
    of the same map, robot radius and seed."""
    import ldcbf_nav

    return [[float(x) for x in g] for g in ldcbf_nav.simulate(name, seed=seed, **lip_overrides(pairs))["subgoals"]]


def run_lip(name: str, pairs: List[str], seed: Optional[int]) -> Dict[str, Any]:
    """The LIP plant (``ldcbf_nav.simulate``, the library of ``ldcbf-sim
    run``) on the same scenario with the G1's settings; its summary."""
    import ldcbf_nav

    return ldcbf_nav.simulate(name, seed=seed, **lip_overrides(pairs))["summary"]


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="python3 -m ldcbf_fullbody", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="walk one scenario with the G1 in MuJoCo")
    run.add_argument("scenario", help="scenario name (scenarios/NAME.toml) or path")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a setting")
    run.add_argument("--seed", type=int, default=None)
    run.add_argument("--out", required=True, type=pathlib.Path, help="output folder")
    run.add_argument("--quiet", action="store_true", help="no line per footstep")
    bat = sub.add_parser("batch", help="many seeds of a scenario family")
    bat.add_argument("--family", required=True, help="a scenario with a [generator]")
    bat.add_argument("--seeds", required=True, help="A..B (B excluded), A..=B or one seed")
    bat.add_argument("--shard", default="1/1", help="run only shard I of N (interleaved), as ldcbf-sim batch")
    bat.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a setting")
    bat.add_argument("--out", type=pathlib.Path, default=None, help="output folder [out/fullbody-batch-<family>[-shard<I>of<N>]]")
    lip = sub.add_parser("lip", help="the LIP plant (ldcbf-sim run) with the G1's settings, for comparison")
    lip.add_argument("scenario")
    lip.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    lip.add_argument("--seed", type=int, default=None)
    wp = sub.add_parser("walk-plan", help="walk a hand-made footstep plan, no controller (plan.KINDS)")
    wp.add_argument("kind", help="in-place, straight or turn")
    wp.add_argument("--steps", type=int, default=20, help="footsteps after the start [20]")
    wp.add_argument("--stride", type=float, default=0.1, help="path advance per step, m [0.1]")
    wp.add_argument("--turn", type=float, default=0.1, help="heading change per step (turn), rad [0.1]")
    wp.add_argument("--step-duration", type=float, default=None, help="s [the derived configuration's]")
    wp.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a sim.Options setting")
    args = parser.parse_args(argv)
    try:
        import ldcbf_nav

        try:
            if args.command == "batch":
                from . import batch

                part = batch.shard(args.shard)
                seeds = batch.shard_seeds(batch.seed_range(args.seeds), part)
                suffix = f"-shard{part[0]}of{part[1]}" if part[1] > 1 else ""
                out = args.out or pathlib.Path(f"out/fullbody-batch-{pathlib.Path(args.family).stem}{suffix}")
                split_sets(args.set)
                rows = batch.run_batch(args.family, seeds, args.set, out, run_one)
                print(batch.verdict(rows))
                return 0
            if args.command == "walk-plan":
                from . import plan

                option_sets, other = split_sets(args.set)
                if other:
                    raise ValueError(f"walk-plan: not a sim.Options setting: {', '.join(other)}")
                T = args.step_duration or robot.derived_config()["step_duration"]
                result = plan.walk(args.kind, args.steps, args.stride, args.turn, T, sim.Options(**option_sets))
                print(" ".join(f"{k}={v}" for k, v in result.items()))
                return 0
            if args.command == "lip":
                lip_summary = run_lip(args.scenario, args.set, args.seed)
                keys = ("outcome", "steps", "sim_time", "final_distance", "status_counts", "min_body_clearance", "min_footstep_clearance", "contacts_robot")
                print(" ".join(f"{k}={lip_summary[k]}" for k in keys))
                return 0
            summary = run_one(args.scenario, args.set, args.out, args.seed, args.quiet)
        except ldcbf_nav.ArgumentError as e:
            raise ValueError(str(e)) from e
    except (ValueError, TypeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    keys = ("reached_goal", "falls", "link_contacts", "landing_error_p95_m", "min_clearance_3d_m", "sim_time", "real_time_factor")
    print(" ".join(f"{k}={summary[k]}" for k in keys))
    return 0
