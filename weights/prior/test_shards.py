"""Tests of the sharded data generation (shards.py): the loader train.py and parity.py share,
and a real local Ray cluster of two workers running `edmp-host gen-data` shards (EDMP_HOST:
the edmp-host binary; scripts/test sets it)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from shards import load_data, shard_name  # noqa: E402

HOST = os.environ.get("EDMP_HOST")


def test_a_folder_of_shards_loads_in_seed_order(tmp_path: Path) -> None:
    # Written out of order; name order is seed order (zero-padded), whatever the file times.
    for seed, value in [(200, 2.0), (0, 0.0), (100, 1.0)]:
        np.save(tmp_path / shard_name(seed), np.full((seed // 100 + 1, 50, 6), value, dtype=np.float32))
    data = load_data(tmp_path)
    assert data.shape == (6, 50, 6)
    assert [float(t[0, 0]) for t in data] == [0.0, 1.0, 1.0, 2.0, 2.0, 2.0]
    single = tmp_path / "one.npy"
    np.save(single, data[:2])
    assert load_data(single).shape == (2, 50, 6)


def test_shards_of_two_arms_are_refused(tmp_path: Path) -> None:
    np.save(tmp_path / shard_name(0), np.zeros((1, 50, 6), dtype=np.float32))
    np.save(tmp_path / shard_name(1), np.zeros((1, 50, 7), dtype=np.float32))
    with pytest.raises(SystemExit, match="different shapes"):
        load_data(tmp_path)


@pytest.mark.skipif(HOST is None, reason="EDMP_HOST (the edmp-host binary) not set")
def test_two_local_workers_write_every_shard_once(tmp_path: Path) -> None:
    pytest.importorskip("ray")
    out = tmp_path / "xarm6"
    cmd = [sys.executable, str(HERE / "shards.py"), "--robot", "xarm6", "--environments", "4", "--shard-size", "1",
           "--seed", "10", "--workers", "2", "--host", str(HOST), "--out", str(out), "--no-progress"]
    subprocess.run(cmd, check=True, capture_output=True, text=True, timeout=600)
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["robot"] == "xarm6"
    assert [s["seed"] for s in manifest["shards"]] == [10, 11, 12, 13]
    assert sorted(p.name for p in out.glob("shard-*.npy")) == [shard_name(s) for s in (10, 11, 12, 13)]
    for s in manifest["shards"]:
        shard = np.load(out / shard_name(s["seed"]))
        assert shard.shape == (s["trajectories"], 50, 6) and s["environments"] == 1
        assert np.isfinite(shard).all()
    data = load_data(out)
    assert data.shape[0] == sum(s["trajectories"] for s in manifest["shards"]) > 0
    # Each shard is gen-data's own run of its seeds: the same environments give the same ends
    # (the candidates are drawn from the seed; only RRT's time budget may drop a pair).
    direct = tmp_path / "direct.npy"
    subprocess.run([str(HOST), "gen-data", "--robot", "xarm6", "--seed", "12", "--environments", "1", "--out",
                    str(direct)], check=True, capture_output=True, timeout=300)
    ends = {tuple(np.round(t[[0, -1]].ravel(), 6)) for t in np.load(direct)}
    shard_ends = {tuple(np.round(t[[0, -1]].ravel(), 6)) for t in np.load(out / shard_name(12))}
    assert ends and shard_ends and ends & shard_ends
    # A second run finds every shard there and runs nothing.
    again = subprocess.run(cmd, check=True, capture_output=True, text=True, timeout=120)
    assert "0 shards to run, 4 already" in again.stderr


def test_a_failing_shard_stops_the_run_and_names_it(tmp_path: Path) -> None:
    pytest.importorskip("ray")
    cmd = [sys.executable, str(HERE / "shards.py"), "--robot", "xarm6", "--environments", "2", "--shard-size", "1",
           "--workers", "1", "--host", "/bin/false", "--out", str(tmp_path / "out"), "--no-progress"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert done.returncode != 0
    assert "a shard failed" in done.stderr and "gen-data exited 1" in done.stderr, done.stderr[-2000:]
    assert not list((tmp_path / "out").glob("shard-*.npy"))
