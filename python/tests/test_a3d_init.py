"""Tests of the Python binding on the shipped fixtures (#28): every function,
results equal to the CLI's output files for the same inputs (MAPF bytes
identical), positioned errors with their kind, and argument checks.

Run from anywhere: ``pytest python/tests``. The CLI binary for the
comparisons is ``$A3D_INIT_BIN``, else ``target/release/a3d-init``, else
``target/debug/a3d-init``; without one those comparisons are skipped, saying
so (CI builds it first).
"""

import logging
import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

import a3d_init

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "fixtures"
SLOPE = FIXTURES / "slope"
SAND = SLOPE / "sand-nodes.csv"
MINI = FIXTURES / "anura3d-mini"


def cli_binary():
    for candidate in (os.environ.get("A3D_INIT_BIN"), ROOT / "target/release/a3d-init", ROOT / "target/debug/a3d-init"):
        if candidate and Path(candidate).is_file():
            return str(candidate)
    if os.environ.get("A3D_INIT_REQUIRE_CLI"):
        raise AssertionError("A3D_INIT_REQUIRE_CLI is set but no a3d-init binary was found")
    pytest.skip("no a3d-init binary to compare with (set A3D_INIT_BIN)")


def test_inspect_gives_the_mps_anura3d_creates():
    model = a3d_init.inspect(SLOPE)
    assert model.computation_method == "MPM-MIXED"
    assert len(model.points["id"]) == 5040
    assert model.points["id"].dtype == np.uint32
    assert model.points["id"][0] == 1 and model.points["element"][0] == 1
    assert {m["name"] for m in model.materials} == {"silty_sand", "compacted_clay"}
    assert np.all(model.points["volume"] > 0)
    assert "5040 MPs" in repr(model)


def test_map_writes_what_the_cli_writes(tmp_path, caplog):
    out = tmp_path / "py"
    with caplog.at_level(logging.INFO, logger="a3d_init"):
        mapped = a3d_init.map(fem=SAND, model=SLOPE, out=out)
    assert mapped["material_points"] == 5040
    assert Path(mapped.folder) == out
    assert "slope.MAPF" in mapped.files
    state = mapped.state
    assert state["total_stress"].shape == (5040, 6)
    assert state["pwp"].shape == (5040,)
    assert np.all(np.isfinite(state["effective_stress"]))
    assert any(r.name == "a3d_init" for r in caplog.records)
    # An existing folder needs force.
    with pytest.raises(a3d_init.OutputError) as e:
        a3d_init.map(fem=SAND, model=SLOPE, out=out)
    assert e.value.kind == "output" and "exists" in str(e.value)
    # The library names the setting; the binding spells it as the keyword.
    assert "replacing an output (force=True)" in str(e.value), str(e.value)
    a3d_init.map(SAND, SLOPE, out, force=True)
    # The binary, same inputs: the same bytes.
    cli_out = tmp_path / "cli"
    subprocess.run([cli_binary(), "map", "--fem", str(SAND), "--mpm", str(SLOPE), "--out", str(cli_out)], check=True, capture_output=True)
    for name in mapped.files:
        if name != "report.json":
            assert (out / name).read_bytes() == (cli_out / name).read_bytes(), name


def test_map_options_are_the_cli_flags(tmp_path):
    mapped = a3d_init.map(SAND, mpm=SLOPE, out=tmp_path / "o", h="auto", kernel="gaussian", stress="zero")
    assert mapped["kernel"] == "gaussian"
    assert mapped["calibration"] is not None
    assert np.all(mapped.state["total_stress"] == 0.0)
    with pytest.raises(ValueError, match="stress"):
        a3d_init.map(SAND, SLOPE, tmp_path / "x", stress="sideways")
    with pytest.raises(ValueError, match="h:"):
        a3d_init.map(SAND, SLOPE, tmp_path / "x", h="-1")


def test_map_at_the_failure_step_of_a_series(tmp_path):
    # #39: FS(t) over the OpenGeoSys series on the model, then the first
    # output with FS <= 1 (1.26 h on the shipped rain) is mapped.
    rain = SLOPE / "ogs" / "results" / "rain.pvd"
    mapped = a3d_init.map(rain, SLOPE, tmp_path / "f", step="failure", material_map={"mat0": "silty_sand"}, stress="geostatic")
    failure = mapped["failure"]
    assert failure["method"] == "morgenstern-price"
    assert failure["factor"] <= 1.0 < failure["before"][1]
    assert failure["time"] == 4536.0
    assert any("step failure" in n for n in mapped["notes"])
    # A single table is no series: an option error, which is a ValueError.
    with pytest.raises(ValueError, match="time series"):
        a3d_init.map(SAND, SLOPE, tmp_path / "x", step="failure")


def test_map_solves_for_equilibrium_and_verify_measures_it(tmp_path):
    out = tmp_path / "eq"
    mapped = a3d_init.map(SAND, SLOPE, out, stress="equilibrium", h=0.046)
    solve = mapped["equilibrium"]
    assert solve["equilibrium"] is True
    assert solve["residual_ratio"] < 1e-6
    assert {m["poisson_from"] for m in solve["materials"]} <= {"k0", "gom", "default"}
    # The state a3d-init intended (mps.csv) is at rest in the runner's
    # equations, with the pore pressure held (the stand-in pwp field is not a
    # seepage solution, so the sand's water flows when it runs two-phase).
    verdict = a3d_init.verify(model=out, state=out / "mps.csv", out=tmp_path / "v", drained=True)
    assert verdict["equilibrium"] is True
    assert verdict["run"]["initial_residual_ratio"] < 1e-6
    gom = a3d_init.map(SAND, SLOPE, tmp_path / "gom", stress="equilibrium", h=0.046, k0_consistent=False)
    assert gom["equilibrium"]["k0_consistent"] is False


def test_interpolate_matches_map_and_reproduces_a_linear_field():
    rng = np.random.default_rng(3)
    nodes = rng.uniform(0, 1, (4000, 2))
    values = np.column_stack([2 * nodes[:, 0] + 3 * nodes[:, 1], np.ones(4000)])
    points = rng.uniform(0.2, 0.8, (500, 2))
    got, shepard, neighbours = a3d_init.interpolate(nodes, values, points, h=0.03)
    assert got.shape == (500, 2) and shepard.shape == (500,) and neighbours.dtype == np.uint32
    # Shepard normalisation reproduces constants exactly, linear fields closely.
    assert np.allclose(got[:, 1], 1.0, atol=1e-12)
    error = np.abs(got[:, 0] - (2 * points[:, 0] + 3 * points[:, 1]))
    assert error.max() < 0.1 and error.mean() < 0.02, (error.max(), error.mean())
    assert np.all(neighbours > 0)
    one, _, _ = a3d_init.interpolate(nodes, values[:, 0].copy(), points, h=0.03)
    assert one.shape == (500,) and np.array_equal(one, got[:, 0])
    # Regions: a point sees only its own region's nodes.
    node_regions = (nodes[:, 0] > 0.5).astype(np.uint32)
    point_regions = (points[:, 0] > 0.5).astype(np.uint32)
    split, _, _ = a3d_init.interpolate(nodes, node_regions.astype(float), points, 0.05, regions=(node_regions, point_regions))
    assert np.array_equal(split, point_regions.astype(float))


def test_interpolate_equals_the_mps_map_writes(tmp_path):
    fem = a3d_init.read_fem(SAND)
    model = a3d_init.inspect(SLOPE)
    mapped = a3d_init.map(SAND, SLOPE, tmp_path / "o", h=0.05, stress="zero")
    sand = model.points["material"] == 1
    mps = np.column_stack([model.points["x"], model.points["y"]])[sand]
    nodes = fem["positions"][:, :2].copy()
    pwp, _, _ = a3d_init.interpolate(nodes, fem["fields"]["pwp"], mps, 0.05, outside="error", min_shepard=0.02)
    # MPM-MIXED: map writes element means; compare per element.
    elements = model.points["element"][sand]
    for e in np.unique(elements)[:200]:
        at = elements == e
        assert np.isclose(pwp[at].mean(), mapped.state["pwp"][sand][at][0], rtol=1e-9, atol=1e-9)


def test_calibrate_finds_the_papers_range():
    fem = a3d_init.read_fem(SAND)
    nodes = fem["positions"][:, :2].copy()
    h, stats = a3d_init.calibrate(nodes, fem["fields"]["pwp"], fields=["pwp"])
    assert 0.7 <= stats["h_over_l"] <= 1.0
    assert h == stats["h"] and stats["fields"] == ["pwp"]
    assert stats["stats"]["r2"] > 0.99


def test_read_fem_converts_signs_and_units():
    fem = a3d_init.read_fem(FIXTURES / "geostudio-csv/k0-slope-hydrostatic.csv")
    assert fem["dim"] == 2 and fem["positions"].shape[1] == 3
    # GeoStudio pwp is positive below the water table; Anura3D's is negative.
    raw = np.loadtxt(FIXTURES / "geostudio-csv/k0-slope-hydrostatic.csv", delimiter=",", skiprows=1)
    assert np.allclose(fem["fields"]["pwp"], -raw[:, 3])
    assert fem["reports"][0]["nodes"] == len(raw)


def test_read_fem_reads_an_ogs_series_in_its_own_signs_and_units():
    # fixtures/slope/ogs: OGS writes Pa, suction negative; step 0 is Table 1's
    # initial saturation 0.31, a uniform suction through van Genuchten (#26).
    rain = SLOPE / "ogs/results/rain.pvd"
    fem = a3d_init.read_fem(rain, step=0)
    alpha, n, s_r = 0.51, 2.73, 0.1
    m = 1 - 1 / n
    suction = (((0.31 - s_r) / (1 - s_r)) ** (-1 / m) - 1) ** (1 / n) / alpha
    assert fem["dim"] == 2
    assert np.allclose(fem["fields"]["pwp"], suction, rtol=1e-9)
    with pytest.raises(a3d_init.A3dInitError, match=r"between step 35 at t = 5580 s \(1.55 h\)"):
        a3d_init.read_fem(rain, step=a3d_init.Time.hours(1.56))
    with pytest.raises(ValueError, match="fem_sign"):
        a3d_init.read_fem(rain, fem_sign="upside-down")


def test_verify_and_fos_on_a_mapped_folder(tmp_path):
    fem = tmp_path / "fem.csv"
    rows = ["X (m),Y (m),PWP (kPa),Material"]
    for j in range(5):
        for i in range(9):
            x, y = 0.25 * i, 0.25 * j
            rows.append(f"{x},{y},{9.81 * (1 - y)},{'clay' if x < 1 else 'sand'}")
    fem.write_text("\n".join(rows) + "\n")
    out = tmp_path / "out"
    a3d_init.map(fem, MINI, out)
    verdict = a3d_init.verify(out)
    assert isinstance(verdict["equilibrium"], bool)
    assert verdict["anura3d"]["mps_csv"]["compared"] == 12
    assert Path(verdict["folder"]) == out / "verify"
    # Held pore pressures on request: p unchanged (both materials are dry).
    held = a3d_init.verify(out, drained=True, force=True)
    assert {f for _, f in held["run"]["formulations"]} == {"dry"}
    assert len(held["run"]["final_pore_pressures"]) == 12
    report = a3d_init.fos(out)
    assert report["factor"] > 0 and Path(report["folder"]) == out / "fos"
    # The state-table form too, and its input is never an output.
    with pytest.raises(a3d_init.OutputError, match="holds the input"):
        a3d_init.fos(model=MINI, state=out / "mps.csv", out=out, force=True)
    assert (out / "mps.csv").is_file()


def test_bad_input_raises_the_positioned_message(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("Node,X (m),Y (m),PWP (kPa)\n1,0,0,1\n2,0,oops,2\n")
    with pytest.raises(a3d_init.InputFileError) as e:
        a3d_init.read_fem(bad)
    assert e.value.kind == "input_file"
    assert re.search(r"bad\.csv:3:\d+: ", str(e.value)), str(e.value)
    with pytest.raises(a3d_init.InputFileError, match=r"TwoMat\.GOM:18:1: element 1"):
        broken = tmp_path / "m"
        broken.mkdir()
        text = (MINI / "TwoMat.GOM").read_text().replace("1 2 5\n", "1 5 2\n", 1)
        (broken / "TwoMat.GOM").write_text(text)
        a3d_init.inspect(broken / "TwoMat.GOM")
    with pytest.raises(a3d_init.A3dInitError):
        a3d_init.inspect(tmp_path / "missing.GOM")


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"nodes": np.zeros((5, 2), dtype=np.float32)}, "nodes"),
        ({"nodes": np.zeros((5, 4))}, "nodes"),
        ({"values": np.zeros(4)}, "values"),
        ({"values": np.zeros(5, dtype=np.int64)}, "values"),
        ({"points": np.zeros((3, 3))}, "points"),
        ({"points": np.zeros(3)}, "points"),
        ({"regions": (np.zeros(5), np.zeros(2))}, "regions"),
    ],
)
def test_wrong_arrays_raise_value_error_naming_the_argument(kwargs, name):
    args = {"nodes": np.zeros((5, 2)), "values": np.zeros(5), "points": np.zeros((3, 2)), "h": 0.1}
    args.update(kwargs)
    with pytest.raises(ValueError, match=f"^{name}"):
        a3d_init.interpolate(**args)


def test_the_readme_example_is_the_shipped_script():
    readme = (ROOT / "python/README.md").read_text()
    block = readme.split("```python\nimport matplotlib", 1)[1].split("```", 1)[0]
    script = (ROOT / "python/examples/h_study.py").read_text()
    assert ("import matplotlib" + block) in script


def test_the_gil_is_released_during_long_work():
    import threading
    import time

    rng = np.random.default_rng(1)
    nodes = rng.uniform(0, 1, (200_000, 3))
    values = nodes[:, 0].copy()
    points = rng.uniform(0, 1, (400_000, 3))
    ticks = []
    done = threading.Event()

    def tick():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=tick)
    t.start()
    start = time.perf_counter()
    a3d_init.interpolate(nodes, values, points, 0.02, node_volume=1 / 200_000)
    end = time.perf_counter()
    done.set()
    t.join()
    during = [x for x in ticks if start < x < end]
    # A held GIL would stop the ticking thread for the whole call; released,
    # it ticks (the scheduler gives it a share of the cores even while the
    # mapper's threads run).
    assert len(during) >= 1, (len(during), end - start)


def test_nothing_reaches_the_terminal_unless_logging_is_configured(tmp_path, capfd):
    fem = tmp_path / "fem.csv"
    fem.write_text("X (m),Y (m),PWP (kPa)\n" + "".join(f"{0.25 * i},{0.25 * j},{9.81 * (1 - 0.25 * j)}\n" for i in range(9) for j in range(5)))
    a3d_init.map(fem, MINI, tmp_path / "out")
    a3d_init.verify(tmp_path / "out", max_steps=50)
    out, err = capfd.readouterr()
    assert out == "" and err == "", (out, err)


def test_a_list_for_an_array_is_a_type_error():
    args = {"nodes": [[0.0, 0.0]] * 5, "values": np.zeros(5), "points": np.zeros((3, 2)), "h": 0.1}
    with pytest.raises(TypeError, match="^nodes"):
        a3d_init.interpolate(**args)


def test_one_exception_hierarchy():
    # Option errors are ValueErrors, file errors OSErrors, all A3dInitErrors.
    assert issubclass(a3d_init.OptionValueError, ValueError)
    assert issubclass(a3d_init.InputFileError, OSError)
    assert issubclass(a3d_init.OutputError, OSError)
    for cls in (a3d_init.OptionValueError, a3d_init.InputFileError, a3d_init.OutputError,
                a3d_init.ModelError, a3d_init.NumericalError):
        assert issubclass(cls, a3d_init.A3dInitError)


def test_wrong_types_raise_type_error_and_wrong_values_value_error(tmp_path):
    with pytest.raises(TypeError, match="^kernel"):
        a3d_init.map(SAND, SLOPE, tmp_path / "x", kernel=3)
    with pytest.raises(TypeError, match="^force"):
        a3d_init.map(SAND, SLOPE, tmp_path / "x", force="yes")
    with pytest.raises(TypeError, match="^columns: expected a dict"):
        a3d_init.map(SAND, SLOPE, tmp_path / "x", columns="pwp=PWP")
    with pytest.raises(TypeError, match="^h"):
        a3d_init.map(SAND, SLOPE, tmp_path / "x", h=[0.05])
    with pytest.raises(TypeError, match="^step"):
        a3d_init.read_fem(SAND, step=1.5)
    with pytest.raises(a3d_init.OptionValueError, match="^kernel: expected one of"):
        a3d_init.map(SAND, SLOPE, tmp_path / "x", kernel="quintic")
    with pytest.raises(ValueError, match="^fem_units"):
        a3d_init.read_fem(SAND, fem_units={"length": "furlong"})
    with pytest.raises(ValueError, match="^fem_units"):
        a3d_init.read_fem(SAND, fem_units={"depth": "m"})
    assert not (tmp_path / "x").exists()


def test_structured_columns_carry_headers_with_commas(tmp_path):
    # A header holding ',' and '=' cannot pass through a `field=header,…`
    # string; the dict carries it whole.
    fem = tmp_path / "fem.csv"
    fem.write_text('X (m),Y (m),"Pressure, pore = u (kPa)"\n0,0,9.81\n1,0,9.81\n0,1,0\n1,1,0\n')
    read = a3d_init.read_fem(fem, columns={"pwp": "Pressure, pore = u (kPa)"})
    # GeoStudio signs: positive below the water table becomes negative.
    assert np.allclose(read["fields"]["pwp"], [-9.81, -9.81, 0.0, 0.0])
    assert a3d_init.read_fem(fem, fem_units={"pressure": "Pa"}, columns={"pwp": "Pressure, pore = u (kPa)"})["dim"] == 2
    # A header that is not there: the library's message, naming the keyword.
    with pytest.raises(a3d_init.InputFileError, match=r"the column mapping \(columns=\) names pwp=nope: no such header"):
        a3d_init.read_fem(fem, columns={"pwp": "nope"})


def test_map_writes_a_cbgeo_project_as_the_cli_does(tmp_path):
    # #41: a CB-Geo run file as the model: the same call writes CB-Geo's files.
    cbgeo = FIXTURES / "cbgeo" / "consolidation"
    fem = cbgeo / "fem-state.csv"
    out = tmp_path / "py"
    mapped = a3d_init.map(fem, cbgeo / "mpm.json", out, stress="fem")
    assert mapped["material_points"] == 600
    assert mapped["cbgeo"]["branch"] == "Fork"
    assert mapped["cbgeo"]["two_phase_particles"] == 600
    assert {"mpm.json", "particles-stresses.txt", "particles-pore-pressures.txt"} <= set(mapped.files)
    # CB-Geo's pore pressure: Pa, compression positive, p = -pwp.
    rows = [line.split() for line in (out / "particles-pore-pressures.txt").read_text().splitlines()]
    p = np.array([float(r[1]) for r in rows])
    assert np.allclose(p, -1000.0 * mapped.state["pwp"], rtol=1e-12, atol=0.0)
    cli_out = tmp_path / "cli"
    subprocess.run([cli_binary(), "map", "--fem", str(fem), "--mpm", str(cbgeo / "mpm.json"), "--stress", "fem", "--out", str(cli_out)], check=True, capture_output=True)
    for name in mapped.files:
        if name != "report.json":
            assert (out / name).read_bytes() == (cli_out / name).read_bytes(), name
