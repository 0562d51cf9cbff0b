"""Hostile messages over Cyclone DDS (issue 38): a peer sends the node, in
`perception: lidar` on `crowded`, each bad message of the issue (scans with
broken metadata, a scan over the ray cap, a stance side out of its values, a
far-future stamp, a clock that jumps back), each in a cycle of its own, and
checks after each one that the node is still up, answers that cycle with a
defined command (`INVALID_INPUT` for what it cannot read, never `SOLVED` on a
scan it could not read) and answers the next good cycle with a plan. The
node's log names each refusal and each clock jump.

Loopback only, as `test_dds.py` (whose Cyclone settings this file shares).
"""

from __future__ import annotations

import math
import subprocess
import time

import pytest

import test_dds as base  # sets CYCLONEDDS_URI before cyclonedds loads
from test_dds import BEST_EFFORT, DOMAIN, NODE, RELIABLE, ROOT, t, wait_for

from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

INVALID_INPUT, SOLVED = 3, 0
INT32_MAX = 2**31 - 1


def stamp(sec: float):
    whole = math.floor(sec)
    return t.Time(sec=int(whole), nanosec=int(round((sec - whole) * 1e9)))


def ring(st, n=360, r=0.6, **spoil):
    inc = 2 * math.pi / n
    fields = dict(
        header=t.Header(stamp=st, frame_id="base_link"),
        angle_min=0.0,
        angle_max=inc * (n - 1),
        angle_increment=inc,
        time_increment=0.0,
        scan_time=0.0,
        range_min=0.0,
        range_max=3.0,
        ranges=[r] * n,
        intensities=[],
    )
    fields.update(spoil)
    return t.LaserScan(**fields)


def odom(st):
    return t.Odometry(header=t.Header(stamp=st, frame_id="map"), child_frame_id="base_link")


def gait(st, side=0):
    return t.GaitState(
        header=t.Header(stamp=st, frame_id="map"),
        stance_side=side,
        stance_foot=t.Point(x=0.0, y=0.1, z=0.0),
        time_in_step=0.1,
    )


@pytest.fixture
def node(tmp_path):
    params = tmp_path / "params.yaml"
    params.write_text(
        "/**:\n  ros__parameters:\n    use_sim_time: true\n"
        "ldcbf_nav:\n  ros__parameters:\n"
        f"    map: crowded\n    perception: lidar\n"
        f"    domain_id: {DOMAIN}\n    localhost_only: true\n"
    )
    proc = subprocess.Popen(
        [NODE, "--params", str(params), "--idle-exit", "30"],
        cwd=ROOT,
        stderr=subprocess.PIPE,
        text=True,
    )
    yield proc
    if proc.returncode is None:
        stop(proc)


def stop(proc) -> str:
    """Stops the node; its log (stderr)."""
    proc.terminate()
    try:
        _, err = proc.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
    print(err)
    return err


def test_bad_messages_get_defined_answers_and_the_node_stays_up(node):
    dp = DomainParticipant(DOMAIN)

    def writer(name, cls, qos):
        return DataWriter(dp, Topic(dp, f"rt{name}", cls, qos=qos), qos=qos)

    goal_w = writer("/goal_pose", t.PoseStamped, RELIABLE)
    odom_w = writer("/odom", t.Odometry, BEST_EFFORT)
    scan_w = writer("/scan", t.LaserScan, BEST_EFFORT)
    gait_w = writer("/gait_state", t.GaitState, RELIABLE)
    cmd_r = DataReader(dp, Topic(dp, "rt/footstep_command", t.FootstepCommand, qos=RELIABLE), qos=RELIABLE)
    diag_r = DataReader(dp, Topic(dp, "rt/diagnostics", t.DiagnosticArray, qos=RELIABLE), qos=RELIABLE)
    wait_for(
        lambda: all(w.get_matched_subscriptions() for w in (goal_w, odom_w, scan_w, gait_w))
        and cmd_r.get_matched_publications()
        and diag_r.get_matched_publications(),
        base.DISCOVERY_S,
        "the node's endpoints",
    )
    goal_w.write(t.PoseStamped(header=t.Header(frame_id="map"), pose=t.Pose(position=t.Point(x=5.0))))
    goal_w.wait_for_acks(5_000_000_000)
    answers = []
    diags = []

    def run_cycle(st, scan, side=0, odom_st=None):
        """Sends one cycle (re-sending the best-effort odometry and scan
        until the command stamped `st` comes) and returns it."""
        o = odom(odom_st or st)
        g = gait(st, side)
        odom_w.write(o)
        scan_w.write(scan)
        gait_w.write(g)
        end = time.monotonic() + base.ANSWER_S
        while True:
            answers.extend(cmd_r.take(N=100))
            diags.extend(diag_r.take(N=100))
            for c in answers:
                if (c.header.stamp.sec, c.header.stamp.nanosec) == (st.sec, st.nanosec):
                    answers.remove(c)
                    return c
            assert node.poll() is None, "the node died"
            assert time.monotonic() < end, f"no command for {st}"
            time.sleep(0.02)
            odom_w.write(o)
            scan_w.write(scan)

    sec = 1.0

    def good():
        nonlocal sec
        sec += 0.05
        st = stamp(sec)
        c = run_cycle(st, ring(st))
        assert c.result != INVALID_INPUT and c.active_obstacles > 0, c
        sec += 0.05

    good()
    nan = float("nan")
    bad_scans = {
        "angle_min NaN": dict(angle_min=nan),
        "angle_min 1e30": dict(angle_min=1e30),
        "range_min NaN": dict(range_min=nan),
        "range_max NaN": dict(range_max=nan),
        "angle_increment NaN": dict(angle_increment=nan),
    }
    for what, spoil in bad_scans.items():
        st = stamp(sec)
        c = run_cycle(st, ring(st, **spoil))
        assert c.result == INVALID_INPUT, (what, c)
        good()
    # 100,000 rays (400 kB): over the ray cap.
    st = stamp(sec)
    c = run_cycle(st, ring(st, n=100_000))
    assert c.result == INVALID_INPUT, c
    good()
    # A stance side out of its values.
    st = stamp(sec)
    c = run_cycle(st, ring(st), side=7)
    assert c.result == INVALID_INPUT and c.status == "invalid_input", c
    good()
    # A far-future stamp, then the normal clock again (a jump back: reset).
    far = t.Time(sec=INT32_MAX, nanosec=0)
    c = run_cycle(far, ring(far))
    assert c.result != INVALID_INPUT, c
    good()
    good()
    # A simulation restarted: time 0.5 again.
    sec = 0.5
    good()
    good()
    assert node.poll() is None
    # Never SOLVED on a scan it could not read: every INVALID_INPUT answer
    # above came with an ERROR diagnostic naming the reason.
    reasons = [s.message for d in diags for s in d.status if s.level == 2]
    assert any("angle_min" in r for r in reasons), reasons
    assert any("rays (3 to 4096)" in r for r in reasons), reasons
    assert any("stance_side = 7" in r for r in reasons), reasons
    counts = {kv.key: int(kv.value) for kv in diags[-1].status[0].values if kv.key.startswith(("rejected", "clock"))}
    assert counts["rejected_scans"] >= 6 and counts["rejected_gait_states"] >= 1, counts
    assert counts["clock_jumps_back"] >= 2, counts
    err = stop(node)
    assert "scan refused: /scan: angle_min = NaN" in err, err
    assert "clock jumped back" in err, err
