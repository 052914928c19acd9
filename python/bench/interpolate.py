"""Speed of ``a3d_init.interpolate`` against the Rust library's own mapper
(``a3d-bench map``) on the same problem: uniform random clouds in the unit
cube, 10^6 nodes and 10^6 points by default, the cubic kernel with about 50
nodes in each support, one field. Prints queries/s for both and their ratio.

    python python/bench/interpolate.py [--nodes N] [--points M] [--bin PATH]

The Python figure times the call alone (arrays made beforehand), best of
``--repeat`` runs, as ``bench map`` does (index build included in both).
"""

import argparse
import math
import re
import subprocess
import time
from pathlib import Path

import numpy as np

import a3d_init

ROOT = Path(__file__).resolve().parents[2]

parser = argparse.ArgumentParser()
parser.add_argument("--nodes", type=int, default=1_000_000)
parser.add_argument("--points", type=int, default=1_000_000)
parser.add_argument("--neighbours", type=float, default=50.0)
parser.add_argument("--repeat", type=int, default=3)
parser.add_argument("--bin", default=str(ROOT / "target/release/a3d-bench"))
args = parser.parse_args()

rng = np.random.default_rng(1)
nodes = rng.uniform(0.0, 1.0, (args.nodes, 3))
points = rng.uniform(0.0, 1.0, (args.points, 3))
values = nodes[:, 0] + 2.0 * nodes[:, 1]
support = (args.neighbours / (args.nodes * 4.0 / 3.0 * math.pi)) ** (1.0 / 3.0)
h = support / 2.0

best = math.inf
for _ in range(args.repeat):
    t = time.perf_counter()
    a3d_init.interpolate(nodes, values, points, h, node_volume=1.0 / args.nodes, outside="nearest")
    best = min(best, time.perf_counter() - t)
python_rate = args.points / best
print(f"python interpolate: {args.nodes} nodes -> {args.points} points, h = {h:.5f}: {best:.3f} s = {python_rate:.3e} queries/s")

if Path(args.bin).is_file():
    out = subprocess.run(
        [args.bin, "map", "--dim", "3", "--nodes", str(args.nodes), "--points", str(args.points),
         "--neighbours", str(args.neighbours), "--repeat", str(args.repeat)],
        check=True, capture_output=True, text=True,
    ).stdout
    rust_rate = float(re.search(r"= ([0-9.e+]+) queries/s", out).group(1))
    print(f"bench map:          {rust_rate:.3e} queries/s")
    print(f"python / rust:      {python_rate / rust_rate:.3f}")
else:
    print(f"no binary at {args.bin}: build it (cargo build --release -p a3d-bench) to compare with bench map")
