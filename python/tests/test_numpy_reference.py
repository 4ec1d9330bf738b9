"""The sweep's physics against an independent implementation: bench/numpy_cs_reference.py, the CS
study written in NumPy from docs/physics.md's equations, against `polrig sweep`'s sweep.csv on a
small 2-D grid.

Tolerance, from double rounding: each ΔV value is kv·v_dec·log10(r) with r = E_j/E_h near 1; the
two codes round E_j, E_h, r and the logarithm differently, a few ulp of r each, i.e. an absolute
error of a few × 2.2e-16 in ln r, so ≈ 0.5·1.02·1e3/ln 10 ≈ 222 mV per unit of ln r times that:
≈ 1e-13 mV per value. Means, SDs (population: differences of values of the same size) and
Eq. 6 inherit errors of that size. We allow 1e-11 mV (100 ×) plus 1e-12 relative (for the
larger columns) — still orders of magnitude below any physical difference (a 1e-3 change of
L_IS changes ASD by ~1e-6 mV). The ratio columns (%) are compared through the same bound
propagated: they divide by BSD or mean_mr, which may be small.
"""
import importlib.util
import math

import numpy as np
import pytest

from conftest import ROOT, read_csv, run_cli

ATOL_MV = 1e-11
RTOL = 1e-12


def load_reference():
    spec = importlib.util.spec_from_file_location("numpy_cs_reference", ROOT / "bench" / "numpy_cs_reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def cli_has_csv_option():
    return "--csv" in run_cli("sweep", "--help").stdout


@pytest.fixture(scope="module")
def sweep_csv(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep") / "out"
    args = ["sweep", "rigs/wang2019-indoor.yaml", "--grid", "eccentricity.L_IS=0.001:1.5:11",
            "--grid", "eccentricity.alpha_S=0:359:13", "-o", out, "--no-plots", "--quiet"]
    if cli_has_csv_option():
        args.append("--csv")
    run_cli(*args)
    return read_csv(out / "sweep.csv")


def test_numpy_reference_matches_polrig_sweep(sweep_csv):
    ref = load_reference()
    rig = ref.load_rig(ROOT / "rigs" / "wang2019-indoor.yaml")
    # The grid's values as polrig wrote them (its grid axes round to 15 digits): the same inputs.
    points = {"L_IS": sweep_csv["eccentricity.L_IS"], "alpha_S": sweep_csv["eccentricity.alpha_S"]}
    assert len(points["L_IS"]) == 11 * 13
    expected = ref.cs_summaries(rig, points)
    for name, values in expected.items():
        got = sweep_csv[name]
        bound = ATOL_MV + RTOL * np.abs(values)
        worst = np.max(np.abs(got - values) / bound)
        assert worst <= 1.0, f"{name}: differs from the NumPy reference by {worst:.3g} × the bound"
    # The figures are not trivially zero: the comparison can fail.
    assert np.all(expected["pair1_bsd_mV"] > 1e-3)
    assert np.ptp(expected["pair2_mean_mr_mV"]) > 1e-2
    for i in (1, 2, 3):
        bsd, asd = expected[f"pair{i}_bsd_mV"], expected[f"pair{i}_asd_mV"]
        pct = 100 * asd / bsd
        bound = 100 * (ATOL_MV / bsd + asd * ATOL_MV / bsd**2) + RTOL * np.abs(pct)
        assert np.all(np.abs(sweep_csv[f"pair{i}_asd_bsd_pct"] - pct) <= bound)
        eq6, mr = expected[f"pair{i}_eq6_mV"], expected[f"pair{i}_mean_mr_mV"]
        defined = np.abs(mr) > 1e-9
        dev = 100 * (eq6[defined] - mr[defined]) / mr[defined]
        bound = 100 * (2 * ATOL_MV / np.abs(mr[defined]) + np.abs(eq6[defined]) * ATOL_MV / mr[defined] ** 2) + 1e-9
        assert np.all(np.abs(sweep_csv[f"pair{i}_eq6_dev_pct"][defined] - dev) <= bound)


def test_numpy_reference_is_the_paper_at_the_default_rig():
    """The reference itself against the paper's closed form: with the port centred (L_IS = 0)
    Eq. 6 is exact and ΔV_mr is constant (docs/physics.md §5)."""
    ref = load_reference()
    rig = ref.load_rig(ROOT / "rigs" / "wang2019-indoor.yaml")
    out = ref.cs_summaries(rig, {"L_IS": np.array([0.0]), "L_S": np.array([0.3])})
    for i in (1, 2, 3):
        assert math.isclose(out[f"pair{i}_mean_mr_mV"][0], out[f"pair{i}_eq6_mV"][0], rel_tol=1e-12)
        assert out[f"pair{i}_asd_mV"][0] < 1e-12
