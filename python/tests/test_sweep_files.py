"""sweep.h5, read by h5py (an HDF5 reader independent of polrig's writer), against sweep.csv; and
Rig.sweep(out=...) writing the CLI's folder through the same library code."""
import shutil

import h5py
import numpy as np
import pytest
import yaml

import polrig
from conftest import ROOT, read_csv, run_cli

INDOOR = ROOT / "rigs" / "wang2019-indoor.yaml"
# L_IS = 0 with a centred sensor: BSD is zero there and ASD/BSD undefined (NaN in both files).
GRID = {"eccentricity.L_IS": "0:1:4", "eccentricity.alpha_S": "0:350:3"}
SETS = ["--set", "eccentricity.L_S=0"]
COLUMNS = [f"pair{i}_{c}" for i in (1, 2, 3) for c in
           ("bsd_mV", "asd_mV", "asd_bsd_pct", "mean_br_mV", "mean_mr_mV", "eq6_mV", "eq6_dev_pct")]


def cli_sweep(out, *extra):
    grid = [a for k, v in GRID.items() for a in ("--grid", f"{k}={v}")]
    return run_cli("sweep", INDOOR, *SETS, *grid, "--steps", 36, "-o", out, "--quiet", *extra)


def test_sweep_h5_holds_sweep_csv_exactly_with_its_axes_as_dimension_scales(tmp_path):
    out = tmp_path / "sw"
    cli_sweep(out, "--csv", "--no-plots")
    csv = read_csv(out / "sweep.csv")
    manifest = yaml.safe_load((out / "manifest.yaml").read_text())
    with h5py.File(out / "sweep.h5", "r") as f:
        keys = list(GRID)
        assert set(f.keys()) == set(COLUMNS) | set(keys)
        for k in keys:
            assert f[k].dtype == np.float64 and f[k].ndim == 1
            assert f[k].attrs["CLASS"] == b"DIMENSION_SCALE"
        assert [f[k].shape[0] for k in keys] == [4, 3]
        L, a = np.meshgrid(f[keys[0]][...], f[keys[1]][...], indexing="ij")
        assert np.array_equal(L.ravel(), csv[keys[0]]) and np.array_equal(a.ravel(), csv[keys[1]])
        assert f[keys[0]].attrs["units"] == "mm" and f[keys[1]].attrs["units"] == "deg"
        nan_seen = False
        for name in COLUMNS:
            d = f[name]
            assert d.shape == (4, 3) and d.dtype == np.float64, name
            values = d[...].ravel()
            # Bit for bit, NaN where the CSV says nan.
            assert np.array_equal(values, csv[name], equal_nan=True), name
            assert np.array_equal(np.isnan(values), np.isnan(csv[name])), name
            nan_seen |= bool(np.isnan(values).any())
            assert d.attrs["units"] in ("mV", "%") and d.attrs["description"].startswith("pair ")
            for dim, k in enumerate(keys):
                assert d.dims[dim].label == "" and len(d.dims[dim]) == 1
                assert d.dims[dim][0].name == "/" + k, (name, dim)
        assert nan_seen, "the grid was meant to hold an undefined ratio"
        attrs = dict(f.attrs)
        assert attrs["program"] == "polrig" and attrs["manifest_schema"] == "1"
        for key in ("version", "git_revision", "command", "working_directory", "rig_file"):
            assert attrs[key] == str(manifest[key]), key
        assert attrs["seed"] == str(manifest["seed"])
        assert attrs["overrides"] == "".join(o + "\n" for o in manifest["overrides"])
        assert attrs["rig_text"] == INDOOR.read_text() == manifest["rig_text"]
        assert attrs["rig_resolved"] == (out / "rig.yaml").read_text() == manifest["rig_resolved"]
    # The manifest lists the HDF5 file beside the CSV.
    assert {"sweep.h5", "sweep.csv"} <= set(manifest["files"])


def test_two_runs_give_the_same_bytes(tmp_path):
    cli_sweep(tmp_path / "a", "--no-plots")
    shutil.move(tmp_path / "a", tmp_path / "first")
    cli_sweep(tmp_path / "a", "--no-plots")
    assert (tmp_path / "a" / "sweep.h5").read_bytes() == (tmp_path / "first" / "sweep.h5").read_bytes()


def test_rig_sweep_out_writes_the_cli_folder(tmp_path, monkeypatch):
    plots = shutil.which("gnuplot") is not None
    monkeypatch.chdir(ROOT)  # the manifests record the working directory; the CLI runs from ROOT
    cli_sweep(tmp_path / "cli", "--csv", *([] if plots else ["--no-plots"]))
    rig = polrig.Rig.load(INDOOR, set={"eccentricity.L_S": 0})
    path = rig.sweep(GRID, steps=36, out=tmp_path / "py", csv=True, plots=plots, threads=1)
    assert path == tmp_path / "py"
    names = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert names == sorted(p.name for p in path.iterdir())
    for name in names:
        if name not in ("manifest.yaml", "sweep.h5"):  # both record the command
            assert (path / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    m_cli = yaml.safe_load((tmp_path / "cli" / "manifest.yaml").read_text())
    m_py = yaml.safe_load((path / "manifest.yaml").read_text())
    assert m_py["command"].startswith("python: polrig.Rig(")
    assert {k: v for k, v in m_py.items() if k != "command"} == {k: v for k, v in m_cli.items() if k != "command"}
    with h5py.File(tmp_path / "cli" / "sweep.h5", "r") as c, h5py.File(path / "sweep.h5", "r") as p:
        assert sorted(c.keys()) == sorted(p.keys())
        for name in c:
            assert c[name][...].tobytes() == p[name][...].tobytes(), name
            assert c[name].attrs["units"] == p[name].attrs["units"]
        assert {k: v for k, v in c.attrs.items() if k != "command"} == \
               {k: v for k, v in p.attrs.items() if k != "command"}
        assert p.attrs["command"] == m_py["command"]
    # The arrays without out= are the file's values.
    res = rig.sweep(GRID, steps=36)
    with h5py.File(path / "sweep.h5", "r") as p:
        for i in range(3):
            assert np.array_equal(res.asd_mV[..., i], p[f"pair{i + 1}_asd_mV"][...])


def test_rig_sweep_out_refuses_what_the_cli_refuses(tmp_path):
    rig = polrig.Rig()
    with pytest.raises(RuntimeError, match="--resume: there is no interrupted run of .* to continue"):
        rig.sweep({"eccentricity.L_S": "0:1:3"}, steps=8, out=tmp_path / "x", resume=True)
    assert not (tmp_path / "x").exists() and not (tmp_path / ".x.resumable").exists()
    rig.sweep({"eccentricity.L_S": "0:1:3"}, steps=8, out=tmp_path / "x")
    with pytest.raises(RuntimeError, match="the output folder exists"):
        rig.sweep({"eccentricity.L_S": "0:1:3"}, steps=8, out=tmp_path / "x")
    with pytest.raises(ValueError, match="options of out="):
        rig.sweep({"eccentricity.L_S": "0:1:3"}, csv=True)


def test_a_three_axis_sweep_in_blocks_that_cut_rows_lands_in_row_major_order(tmp_path):
    # 7429 points: the first block (4096 points) ends inside a plane and inside a row.
    grid = {"eccentricity.L_IS": "0:1:17", "eccentricity.alpha_S": "0:360:19", "eccentricity.L_S": "0.1:2:23"}
    out = tmp_path / "sw3"
    run_cli("sweep", INDOOR, *[a for k, v in grid.items() for a in ("--grid", f"{k}={v}")], "--steps", 8,
            "-o", out, "--quiet", "--csv")
    csv = read_csv(out / "sweep.csv")
    assert not (out / "sweep_map.csv").exists()  # no plots for three axes
    with h5py.File(out / "sweep.h5", "r") as f:
        axes = [f[k][...] for k in grid]
        mesh = np.meshgrid(*axes, indexing="ij")
        for k, m in zip(grid, mesh):
            assert np.array_equal(m.ravel(), csv[k]), k
        for name in COLUMNS:
            assert f[name].shape == (17, 19, 23)
            assert np.array_equal(f[name][...].ravel(), csv[name], equal_nan=True), name


def test_rig_sweep_resumes_a_killed_cli_sweep_to_the_cli_folder(tmp_path, monkeypatch):
    """kill -9 of `polrig sweep` after its first checkpoint, then Rig.sweep(out=, resume=True): the
    folder is the uninterrupted CLI run's, byte for byte (its manifest keeps the CLI's command)."""
    import os
    import signal
    import subprocess
    import time
    from conftest import polrig_exe
    monkeypatch.chdir(ROOT)
    grid = {"eccentricity.L_S": "0.001:1:400", "eccentricity.L_IS": "0.001:1:500"}  # 200,000 points
    out = tmp_path / "sw"
    args = [str(polrig_exe()), "sweep", str(INDOOR), *[a for k, v in grid.items() for a in ("--grid", f"{k}={v}")],
            "--csv", "--no-plots", "--threads", "1", "--quiet", "-o", str(out)]
    subprocess.run(args, check=True, capture_output=True, cwd=ROOT)
    shutil.move(out, tmp_path / "reference")
    p = subprocess.Popen(args, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    record = tmp_path / ".sw.resumable" / "resume-state.yaml"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            if yaml.safe_load(record.read_text())["points_done"] > 0:
                break
        except (OSError, TypeError, KeyError, yaml.YAMLError):
            pass
        time.sleep(0.001)
    os.kill(p.pid, signal.SIGKILL)
    p.wait()
    assert p.returncode == -signal.SIGKILL, "the sweep ended before it was killed"
    assert not out.exists() and record.exists()
    with pytest.raises(RuntimeError, match="--resume continues it; --force starts over"):
        polrig.Rig.load(INDOOR).sweep(grid, out=out, csv=True, threads=1)
    with pytest.raises(RuntimeError, match=r"was started with another csv \(--csv\)"):
        polrig.Rig.load(INDOOR).sweep(grid, out=out, resume=True, threads=1)
    polrig.Rig.load(INDOOR).sweep(grid, out=out, csv=True, resume=True, threads=2)
    ref = tmp_path / "reference"
    assert sorted(x.name for x in out.iterdir()) == sorted(x.name for x in ref.iterdir())
    for x in ref.iterdir():
        assert (out / x.name).read_bytes() == x.read_bytes(), x.name


def read_map(path):
    """sweep_map.csv: a header, then rows of numbers with a blank line after each scan line."""
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    rows = [[float(c) for c in l.split(",")] for l in lines[1:] if l]
    return header, np.array(rows)


@pytest.mark.skipif(shutil.which("gnuplot") is None, reason="needs gnuplot")
def test_the_image_plots_data_is_the_grid_or_its_bin_means(tmp_path):
    # 300 × 7: the first axis is cut into 256 bins (point i into bin ⌊i·256/300⌋), the second is exact.
    out = tmp_path / "img"
    run_cli("sweep", INDOOR, "--grid", "eccentricity.L_IS=0.001:1:300", "--grid", "eccentricity.alpha_S=0:360:7",
            "--steps", 8, "-o", out, "--quiet")
    header, m = read_map(out / "sweep_map.csv")
    assert header == ["eccentricity.alpha_S", "eccentricity.L_IS", "pair1_asd_mV", "pair1_mean_mr_mV"]
    assert m.shape == (256 * 7, 4)
    assert (out / "sweep_map.csv").read_text().count("\n\n") == 256  # a blank line after each scan line
    with h5py.File(out / "sweep.h5", "r") as f:
        L, alpha = f["eccentricity.L_IS"][...], f["eccentricity.alpha_S"][...]
        for col, name in ((2, "pair1_asd_mV"), (3, "pair1_mean_mr_mV")):
            values = f[name][...]
            # The same additions in the same (grid) order as the writer: np.add.at is unbuffered.
            sums, counts = np.zeros((256, 7)), np.zeros((256, 7))
            bins = np.arange(300) * 256 // 300
            for i in range(300):
                np.add.at(sums, (bins[i], np.arange(7)), values[i])
                counts[bins[i]] += 1
            assert np.array_equal(m[:, col], (sums / counts).ravel()), name
    centres = L[0] + (np.arange(256) + 0.5) * (L[-1] - L[0]) / 256
    assert np.array_equal(m[:, 1], np.repeat(centres, 7))
    assert np.array_equal(m[:, 0], np.tile(alpha, 256))  # exact: one pixel per value
