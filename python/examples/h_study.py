"""Parametric study of the smoothing length h over the shipped slope: the
leave-one-out error and the mapped pore pressure at the toe for h from 0.5 l
to 2 l, with the calibrated optimum marked. Run from the repository root:
``python python/examples/h_study.py`` (needs matplotlib); writes h_study.png.
This is the worked example of python/README.md, kept identical by
python/tests/test_a3d_init.py."""

import matplotlib.pyplot as plt
import numpy as np
import a3d_init

fem = a3d_init.read_fem("fixtures/slope/sand-nodes.csv")
nodes = fem["positions"][:, :2].copy()
pwp = fem["fields"]["pwp"]
h_opt, stats = a3d_init.calibrate(nodes, pwp)
l = stats["spacing"]

model = a3d_init.inspect("fixtures/slope")
sand = model.points["material"] == 1
mps = np.column_stack([model.points["x"], model.points["y"]])[sand]

hs = np.linspace(0.5 * l, 2.0 * l, 16)
toe = np.argmin(mps[:, 0] + mps[:, 1])          # the MP nearest the toe
at_toe = [a3d_init.interpolate(nodes, pwp, mps, h)[0][toe] for h in hs]
curve = np.array(stats["curve"])

fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
a.semilogy(curve[:, 0] / l, curve[:, 1]); a.axvline(h_opt / l, ls="--", c="r")
a.set_xlabel("h / l"); a.set_ylabel("leave-one-out error Σ|e| (kPa)")
b.plot(hs / l, at_toe, "o-"); b.axvline(h_opt / l, ls="--", c="r")
b.set_xlabel("h / l"); b.set_ylabel("pwp at the toe MP (kPa)")
fig.tight_layout(); fig.savefig("h_study.png")
