"""The `ldcbf-ros2` node against an independent DDS (Cyclone DDS, the DDS of
ROS 2's `rmw_cyclonedds`), with ROS 2's topic and type naming.

The first test plays the robot: it publishes the inputs of a recorded `ldcbf-sim`
run (`ldcbf-ros2 record circles`: `/goal_pose` once, then `/odom` and
`/gait_state` per control cycle, in lockstep) and checks that each
`/footstep_command` equals the Rust controller's command on those inputs
field for field, bit for bit, cycle for cycle, and that `/footsteps`
(`nav_msgs/Path`), `/markers` (`visualization_msgs/MarkerArray`) and
`/diagnostics` (`diagnostic_msgs/DiagnosticArray`) arrive with every cycle.
The second closes the loop with the stand-in: `ldcbf-ros2 robot` and the node,
two processes, walk `circles` (known map) and `crowded` (LiDAR: the node
plans on the stand-in's `/scan`) to their goals.
Loopback only (Cyclone on 127.0.0.1 without multicast, the node with
`localhost_only`), on a domain id of its own, bounded in time.

Binaries: `$LDCBF_ROS2` (default `target/debug/ldcbf-ros2`).
`pip install cyclonedds pytest`; `python3 -m pytest ros2/tests/python`.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
NODE = os.environ.get("LDCBF_ROS2", str(ROOT / "target" / "debug" / "ldcbf-ros2"))
DOMAIN = 100 + os.getpid() % 100
SCENARIO = "circles"
# Seconds: discovery, one cycle's answer, the whole test.
DISCOVERY_S, ANSWER_S, TOTAL_S = 30.0, 10.0, 150.0

# Loopback only, unicast discovery to 127.0.0.1 (set before cyclonedds loads).
os.environ["CYCLONEDDS_URI"] = (
    "<CycloneDDS><Domain Id='any'><General>"
    "<Interfaces><NetworkInterface address='127.0.0.1'/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
    "<MaxAutoParticipantIndex>30</MaxAutoParticipantIndex>"
    "<Peers><Peer address='127.0.0.1'/></Peers></Discovery>"
    "</Domain></CycloneDDS>"
)

from cyclonedds.core import Qos, Policy  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
import ros2_types as t  # noqa: E402

RELIABLE = Qos(
    Policy.Reliability.Reliable(max_blocking_time=1_000_000_000),
    Policy.Durability.Volatile,
    Policy.History.KeepLast(1000),
)
BEST_EFFORT = Qos(
    Policy.Reliability.BestEffort,
    Policy.Durability.Volatile,
    Policy.History.KeepLast(5),
)


def wait_for(pred, timeout: float, what: str):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return
        time.sleep(0.02)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


@pytest.fixture(scope="module")
def played(tmp_path_factory):
    d = tmp_path_factory.mktemp("dds")
    params = d / "params.yaml"
    params.write_text(
        "ldcbf_nav:\n  ros__parameters:\n"
        f"    map: {SCENARIO}\n    frame_id: map\n"
        f"    domain_id: {DOMAIN}\n    localhost_only: true\n"
    )
    data = d / "played.json"
    subprocess.run(
        [NODE, "record", SCENARIO, str(data), "--params", str(params)],
        check=True,
        cwd=ROOT,
        timeout=300,
    )
    return params, json.loads(data.read_text())


def test_node_commands_equal_the_controllers(played):
    params, rec = played
    start = time.monotonic()
    node = subprocess.Popen(
        [NODE, "--params", str(params), "--idle-exit", "30"],
        cwd=ROOT,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        run_robot(rec, start)
    finally:
        node.terminate()
        try:
            _, err = node.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            node.kill()
            _, err = node.communicate()
        print(err)


@pytest.mark.parametrize("scenario,perception", [("circles", "map"), ("crowded", "lidar")])
def test_stand_in_closes_the_loop_over_dds(tmp_path, scenario, perception):
    """Two processes, the node and `ldcbf-ros2 robot` (the simulator's plant),
    walk the scenario to its goal over DDS; with LiDAR the node plans on the
    stand-in's `/scan` only."""
    params = tmp_path / "params.yaml"
    params.write_text(
        "ldcbf_nav:\n  ros__parameters:\n"
        f"    map: {scenario}\n    perception: {perception}\n"
        f"    domain_id: {DOMAIN}\n    localhost_only: true\n"
    )
    node = subprocess.Popen(
        [NODE, "--params", str(params), "--idle-exit", "10"],
        cwd=ROOT,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        robot = subprocess.run(
            [NODE, "robot", "--params", str(params)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=400,
        )
    finally:
        node.terminate()
        node.communicate(timeout=10)
    assert robot.returncode == 0, robot.stderr
    assert "GoalReached" in robot.stdout, robot.stdout


def run_robot(rec, start):
    dp = DomainParticipant(DOMAIN)

    def writer(name, cls, qos):
        return DataWriter(dp, Topic(dp, f"rt{name}", cls, qos=qos), qos=qos)

    def reader(name, cls):
        return DataReader(dp, Topic(dp, f"rt{name}", cls, qos=RELIABLE), qos=RELIABLE)

    goal_w = writer("/goal_pose", t.PoseStamped, RELIABLE)
    odom_w = writer("/odom", t.Odometry, BEST_EFFORT)
    gait_w = writer("/gait_state", t.GaitState, RELIABLE)
    cmd_r = reader("/footstep_command", t.FootstepCommand)
    path_r = reader("/footsteps", t.Path)
    markers_r = reader("/markers", t.MarkerArray)
    diag_r = reader("/diagnostics", t.DiagnosticArray)
    readers = [cmd_r, path_r, markers_r, diag_r]
    # Discovery: every endpoint matched with the node's.
    wait_for(
        lambda: all(w.get_matched_subscriptions() for w in (goal_w, odom_w, gait_w))
        and all(r.get_matched_publications() for r in readers),
        DISCOVERY_S,
        "the node's endpoints (discovery on 127.0.0.1)",
    )
    goal_w.write(t.build(t.PoseStamped, rec["goal"]))
    goal_w.wait_for_acks(5_000_000_000)
    got = {id(r): [] for r in readers}

    def take_all():
        for r in readers:
            got[id(r)].extend(r.take(N=100))

    cycles = rec["cycles"]
    for k, c in enumerate(cycles):
        assert time.monotonic() - start < TOTAL_S, f"out of time at cycle {k}"
        odom = t.build(t.Odometry, c["odom"])
        gait = t.build(t.GaitState, c["gait"])
        # Lockstep: the odometry (best effort) until the command of this
        # cycle arrives; the gait state (reliable) once.
        odom_w.write(odom)
        gait_w.write(gait)
        end = time.monotonic() + ANSWER_S
        while len(got[id(cmd_r)]) <= k:
            assert time.monotonic() < end, f"no command for cycle {k}"
            time.sleep(0.005)
            take_all()
            if len(got[id(cmd_r)]) <= k:
                odom_w.write(odom)
        cmd = got[id(cmd_r)][k]
        assert t.as_dict(cmd) == c["command"], f"cycle {k}: the node's command differs"
    wait_for(
        lambda: take_all() or all(len(got[id(r)]) >= len(cycles) for r in readers),
        ANSWER_S,
        "the last cycle's path, markers and diagnostics",
    )
    assert [len(got[id(r)]) for r in readers] == [len(cycles)] * 4
    for k, (p, m, d) in enumerate(zip(got[id(path_r)], got[id(markers_r)], got[id(diag_r)])):
        stamp = t.as_dict(cycles[k]["gait"]["header"]["stamp"])
        assert t.as_dict(p.header.stamp) == stamp
        feet = [t.as_dict(q.pose.position) for q in p.poses]
        assert feet == cycles[k]["command"]["planned_feet"]
        ns = {x.ns for x in m.markers}
        assert {"obstacles", "half_planes", "planned_feet", "predicted_com"} <= ns
        keys = {kv.key for kv in d.status[0].values}
        assert {"cycle_time_us", "relax_gait", "relax_safety"} <= keys
    print(f"{len(cycles)} cycles over DDS in {time.monotonic() - start:.1f} s")
