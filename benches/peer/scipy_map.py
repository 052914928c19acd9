#!/usr/bin/env python3
"""Peer for `a3d-bench e2e` (#17): the same cubic-spline Shepard mapping in
scipy (cKDTree, all threads), compute only: read the FEM CSV and the MP positions,
map pwp and the six total stresses, no output written.

Usage: scipy_map.py FEM_CSV MPS_CSV H
  FEM_CSV  x,y,z,pwp,sxx,syy,szz,sxy,syz,sxz table (header line first)
  MPS_CSV  mps.csv written by `a3d-init map` (x, y, z columns are used)
  H        smoothing length (support 2h)
"""
import sys, time
import numpy as np
from scipy.spatial import cKDTree


def cubic(q):
    w = np.where(q < 1.0, 1.0 - 1.5 * q**2 + 0.75 * q**3, 0.25 * (2.0 - q) ** 3)
    return np.where(q < 2.0, w, 0.0)


def main():
    fem_path, mps_path, h = sys.argv[1], sys.argv[2], float(sys.argv[3])
    t0 = time.time()
    fem = np.loadtxt(fem_path, delimiter=",", skiprows=1)
    mps = np.loadtxt(mps_path, delimiter=",", skiprows=1, usecols=(4, 5, 6))
    t1 = time.time()
    tree = cKDTree(fem[:, :3])
    lists = tree.query_ball_point(mps, 2.0 * h, workers=-1)
    out = np.zeros((len(mps), fem.shape[1] - 3))
    for i, idx in enumerate(lists):
        if not idx:
            continue
        d = np.linalg.norm(fem[idx, :3] - mps[i], axis=1)
        w = cubic(d / h)
        out[i] = w @ fem[idx, 3:] / w.sum()
    t2 = time.time()
    print(f"read {t1 - t0:.2f} s, compute {t2 - t1:.2f} s, {len(mps)} MPs, {len(fem)} nodes")


if __name__ == "__main__":
    main()
