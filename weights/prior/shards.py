"""Training data for an arm's prior, split into shards that run as Ray tasks.

One machine makes about 50-80 trajectories a second (weights/README.md); MpiNets trained on
3.27 M. This runs `edmp-host gen-data --robot NAME --seed S --environments E` once per shard,
each shard a disjoint range of environment seeds, as tasks on a Ray cluster: a local one with
`--workers N` processes by default, or the cluster at `--address` (`ray start --head` on one
machine, `ray start --address HEAD:6379` on the others; every node needs the `edmp-host` binary
at the same path, `--host`). Each task sends its `.npy` bytes back to this driver, which writes
`OUT/shard-SSSSSSSSSS.npy` (named by first seed) and `OUT/manifest.json`, so no shared file
system is needed. Shards already in OUT are kept (a stopped run resumes). `train.py --data OUT`
reads the folder as it is: the shards in name order, concatenated (`load_data`).

    python3 weights/prior/shards.py --robot iiwa7 --environments 3300 --shard-size 100 \\
        --workers 2 --out target/arm-data/iiwa7
"""

from __future__ import annotations

import argparse
import io
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HORIZON = 50
SHARD_GLOB = "shard-*.npy"


def shard_name(seed: int) -> str:
    return f"shard-{seed:010d}.npy"


def load_data(path: str | os.PathLike[str]) -> np.ndarray:
    """An `.npy` file from `gen-data`, or a folder of shards (this script's output) as one
    array: the shards in name order (first seed), concatenated. Shape (N, 50, J)."""
    p = Path(path)
    if not p.is_dir():
        return np.load(p)
    files = sorted(p.glob(SHARD_GLOB))
    if not files:
        sys.exit(f"{p}: no {SHARD_GLOB} in this folder (weights/prior/shards.py writes them)")
    parts = [np.load(f) for f in files]
    shapes = {a.shape[1:] for a in parts}
    if len(shapes) != 1:
        sys.exit(f"{p}: shards of different shapes {sorted(shapes)} (two arms in one folder?)")
    return np.concatenate(parts)


def run_shard(host: str, robot: str, seed: int, environments: int) -> dict:
    """One shard on whichever worker Ray picked: gen-data on one thread (the task holds one
    CPU), its `.npy` bytes returned."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "shard.npy")
        began = time.time()
        done = subprocess.run(
            [host, "gen-data", "--robot", robot, "--seed", str(seed), "--environments", str(environments), "--out", out],
            capture_output=True,
            text=True,
            env={**os.environ, "RAYON_NUM_THREADS": "1"},
        )
        if done.returncode != 0:
            raise RuntimeError(f"shard {seed}: {host} gen-data exited {done.returncode}: {done.stderr.strip()[-2000:]}")
        with open(out, "rb") as f:
            data = f.read()
    return {
        "seed": seed,
        "environments": environments,
        "bytes": data,
        "seconds": round(time.time() - began, 2),
        "worker": f"{os.uname().nodename}:{os.getpid()}",
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robot", required=True, help="the arm (a scene's `robot` name)")
    ap.add_argument("--environments", type=int, required=True, help="environments in all (seeds seed .. seed+N)")
    ap.add_argument("--shard-size", type=int, default=100, help="environments per shard (one Ray task)")
    ap.add_argument("--seed", type=int, default=0, help="first environment seed")
    ap.add_argument("--out", required=True, help="folder for the shards and manifest.json")
    ap.add_argument("--workers", type=int, default=None, help="local cluster: this many worker processes")
    ap.add_argument("--address", default=None, help="an existing Ray cluster (e.g. auto, or HEAD:6379)")
    ap.add_argument("--host", default="target/release/edmp-host", help="the edmp-host binary, on every node")
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args()
    if args.environments < 1 or args.shard_size < 1:
        sys.exit("--environments and --shard-size must be at least 1")
    if args.address is not None and args.workers is not None:
        sys.exit("--workers sizes a local cluster; an existing one (--address) has its own")
    host = os.path.abspath(args.host)
    if not os.access(host, os.X_OK):
        sys.exit(f"--host {args.host}: not an executable (cargo build --release -p edmp-host)")

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    manifest_path = out / "manifest.json"
    manifest = json.loads(manifest_path.read_text()) if manifest_path.exists() else {"robot": args.robot, "shards": []}
    if manifest["robot"] != args.robot:
        sys.exit(f"{out}: holds {manifest['robot']}'s shards, not {args.robot}'s")
    have = {s["seed"] for s in manifest["shards"] if (out / shard_name(s["seed"])).exists()}
    manifest["shards"] = [s for s in manifest["shards"] if s["seed"] in have]
    todo = []
    for first in range(args.seed, args.seed + args.environments, args.shard_size):
        size = min(args.shard_size, args.seed + args.environments - first)
        if first not in have:
            todo.append((first, size))
    print(f"{len(todo)} shards to run, {len(have)} already in {out}", file=sys.stderr)
    if not todo:
        return

    import ray
    from tqdm import tqdm

    if args.address is not None:
        ray.init(address=args.address, log_to_driver=False)
    else:
        ray.init(num_cpus=args.workers or os.cpu_count(), include_dashboard=False, log_to_driver=False)
    task = ray.remote(num_cpus=1, max_retries=2)(run_shard)
    pending = [task.remote(host, args.robot, seed, size) for seed, size in todo]
    began = time.time()
    workers = set()
    with tqdm(total=len(todo), unit="shard", disable=args.no_progress) as bar:
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            try:
                r = ray.get(ready[0])
            except ray.exceptions.RayError as e:
                # The shards done so far are kept: the next run resumes after them.
                ray.shutdown()
                sys.exit(f"a shard failed, {len(pending)} left undone: {e}")
            workers.add(r["worker"])
            data = np.load(io.BytesIO(r.pop("bytes")))
            if data.ndim != 3 or data.shape[1] != HORIZON:
                sys.exit(f"shard {r['seed']}: expected (N, {HORIZON}, J), got {data.shape}")
            tmp = out / (shard_name(r["seed"]) + ".part")
            with open(tmp, "wb") as f:
                np.save(f, data)
            tmp.rename(out / shard_name(r["seed"]))
            manifest["shards"].append({**r, "trajectories": int(data.shape[0])})
            manifest["shards"].sort(key=lambda s: s["seed"])
            manifest_path.write_text(json.dumps(manifest, indent=1) + "\n")
            bar.update(1)
    ray.shutdown()
    total = sum(s["trajectories"] for s in manifest["shards"])
    print(
        f"{len(todo)} shards in {time.time() - began:.1f} s on {len(workers)} workers; "
        f"{total} trajectories in {len(manifest['shards'])} shards in {out}",
        file=sys.stderr,
    )


if __name__ == "__main__":
    main()
