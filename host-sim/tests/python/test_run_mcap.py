"""`run.mcap` read back by an independent reader (the `mcap` package from PyPI).

Runs `ldcbf-sim run maze` (the binary in `$LDCBF_SIM`, default
`target/debug/ldcbf-sim`) and checks, against the CSV logs of the same run:
the channels, their schemas and encodings, the message counts per topic, log
times from simulated time, and the diagnostics equal `cycles.csv` row by row.
`pip install mcap pytest`; `python3 -m pytest host-sim/tests/python`.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
from collections import Counter
from pathlib import Path

import pytest
from mcap.reader import make_reader

ROOT = Path(__file__).resolve().parents[3]
SIM = os.environ.get("LDCBF_SIM", str(ROOT / "target" / "debug" / "ldcbf-sim"))

SCHEMAS = {
    "/tf": "foxglove.FrameTransform",
    "/com_path": "foxglove.PosesInFrame",
    "/footsteps": "foxglove.SceneUpdate",
    "/obstacles": "foxglove.SceneUpdate",
    "/goal": "foxglove.SceneUpdate",
    "/perceived_obstacles": "foxglove.SceneUpdate",
    "/half_planes": "foxglove.SceneUpdate",
    "/plan": "foxglove.SceneUpdate",
    "/diagnostics": "ldcbf.CycleDiagnostics",
}


def rows(path: Path) -> list[dict[str, str]]:
    with path.open() as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("maze") / "out"
    subprocess.run(
        [SIM, "run", "maze", "--out", str(out), "--no-plots"],
        check=True,
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        timeout=600,
    )
    return out


def read(path: Path):
    with path.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        msgs = [(ch.topic, sc, ch, m) for sc, ch, m in reader.iter_messages(log_time_order=True)]
    return summary, msgs


def test_channels_schemas_counts(run: Path):
    summary, msgs = read(run / "run.mcap")
    channels = {ch.topic: ch for ch in summary.channels.values()}
    assert set(channels) == set(SCHEMAS)
    for topic, ch in channels.items():
        sc = summary.schemas[ch.schema_id]
        assert (sc.name, sc.encoding, ch.message_encoding) == (SCHEMAS[topic], "jsonschema", "json")
        assert json.loads(sc.data)["type"] == "object"
    counts = Counter(topic for topic, *_ in msgs)
    cycles = rows(run / "cycles.csv")
    feet = rows(run / "footsteps.csv")
    traj = rows(run / "trajectory.csv")
    want = {
        "/tf": len(traj),
        "/com_path": len(feet),
        "/footsteps": len(feet),
        "/obstacles": 1,
        "/goal": 1,
        "/half_planes": len(cycles),
        "/plan": len(cycles),
        "/diagnostics": len(cycles),
    }
    for topic, n in want.items():
        assert counts[topic] == n, topic
    assert counts["/perceived_obstacles"] == 0  # maze: known map
    # The file's own statistics agree.
    stats = summary.statistics.channel_message_counts
    for cid, ch in summary.channels.items():
        assert stats.get(cid, 0) == counts[ch.topic], ch.topic


def test_times_and_diagnostics(run: Path):
    _, msgs = read(run / "run.mcap")
    cycles = rows(run / "cycles.csv")
    diags = [(m, json.loads(m.data)) for topic, _, _, m in msgs if topic == "/diagnostics"]
    assert len(diags) == len(cycles)
    for row, (m, d) in zip(cycles, diags):
        # Log time is simulated time (cycles.csv prints t with 3 decimals).
        assert abs(m.log_time * 1e-9 - float(row["t"])) < 1e-6
        assert m.log_time == d["timestamp"]["sec"] * 10**9 + d["timestamp"]["nsec"]
        assert d["status"] == row["status"] and d["source"] == row["source"]
        assert d["iterations"] == int(row["iterations"])
        assert d["foot_target"]["x"] == float(row["foot_x"])
        assert d["foot_target"]["y"] == float(row["foot_y"])
        assert d["turning_rate"] == float(row["omega"])
    times = [m.log_time for *_, m in msgs]
    assert times == sorted(times)
    # The obstacles: one line loop per polygon of the map, at t = 0.
    obs = [json.loads(m.data) for topic, _, _, m in msgs if topic == "/obstacles"][0]
    assert len(obs["entities"]) > 0
    assert all(e["lines"][0]["type"] == 1 for e in obs["entities"])
    # The last /com_path holds the path up to the last footstep.
    feet = rows(run / "footsteps.csv")
    path = [json.loads(m.data) for topic, _, _, m in msgs if topic == "/com_path"][-1]
    assert len(path["poses"]) == int(float(feet[-1]["t"]) / 0.05 + 1e-9) + 1
