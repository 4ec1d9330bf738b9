"""polrig.Rig: files, YAML strings and dicts in; YAML out; every key with the checks of --set."""
import copy
import pickle

import numpy as np
import pytest

import polrig
from conftest import ROOT, run_cli

INDOOR = str(ROOT / "rigs" / "wang2019-indoor.yaml")


def test_default_rig_is_the_indoor_rig_file():
    assert polrig.Rig().to_yaml() == polrig.Rig.load(INDOOR).to_yaml()


def test_to_yaml_is_the_cli_rig_show(tmp_path):
    r = polrig.Rig.load(INDOOR, set={"eccentricity.L_S": 0.05, "seed": 7})
    shown = run_cli("rig", "show", INDOOR, "--set", "eccentricity.L_S=0.05", "--set", "seed=7").stdout
    assert r.to_yaml() == shown


def test_yaml_and_dict_round_trips_for_every_rig_file():
    for f in sorted((ROOT / "rigs").glob("*.yaml")):
        r = polrig.Rig.load(f)  # a pathlib.Path
        again = polrig.Rig.from_yaml(r.to_yaml(), origin=str(f))
        assert again.to_yaml() == r.to_yaml(), f.name
        d = r.to_dict()
        # the scene path is relative to the rig file; a dict has no folder of its own
        if "source.scene" in d:
            d["source.scene"] = str(f.parent / d["source.scene"])
        from_dict = polrig.Rig.from_dict(d)
        assert from_dict.to_dict().keys() == d.keys(), f.name
        for k, v in d.items():
            assert np.array_equal(from_dict[k], v) if isinstance(v, np.ndarray) else from_dict[k] == v, (f.name, k)


def test_keys_read_and_set_in_their_units():
    r = polrig.Rig()
    assert r["eccentricity.L_IS"] == 0.05  # rigs/wang2019-indoor.yaml: "L_IS: 0.05"
    r["eccentricity.L_IS"] = 0.1
    assert r["eccentricity.L_IS"] == 0.1
    r["eccentricity.alpha_S"] = np.float64(45)
    r["schedule.samples_per_stop"] = np.int64(3)
    assert r["schedule.samples_per_stop"] == 3 and isinstance(r["schedule.samples_per_stop"], int)
    axes = r["device.film_axes_deg"]
    assert axes.dtype == np.float64 and axes.shape == (6,)
    np.testing.assert_array_equal(axes, [0, 90, 60, 150, 120, 210])
    r["device.film_axes_deg"] = axes + 1
    np.testing.assert_array_equal(r["device.film_axes_deg"], axes + 1)
    assert r["source.model"] == "cos4"
    assert r.overrides[-1].startswith("device.film_axes_deg=")


def test_bad_value_raises_the_cli_message_and_leaves_the_rig():
    r = polrig.Rig.load(INDOOR)
    before = r.to_yaml()
    with pytest.raises(polrig.RigError) as e:
        r["eccentricity.L_IS"] = -1
    cli = run_cli("rig", "show", INDOOR, "--set", "eccentricity.L_IS=-1", check=False)
    assert cli.returncode == 2
    assert str(e.value) in cli.stderr
    assert "eccentricity.L_IS" in str(e.value) and "-1" in str(e.value)
    assert r.to_yaml() == before
    with pytest.raises(polrig.RigError, match=r"got .nan."):
        r["eccentricity.L_S"] = float("nan")
    assert isinstance(polrig.RigError("x"), ValueError)


def test_file_errors_name_file_and_line(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("eccentricity:\n  L_IS: 0.1\n  L_S: -3\n")
    with pytest.raises(polrig.RigError, match=r"bad\.yaml:3: key 'eccentricity\.L_S'"):
        polrig.Rig.load(str(bad))
    with pytest.raises(polrig.RigError, match="no such file"):
        polrig.Rig.load(str(tmp_path / "missing.yaml"))


def test_unknown_key():
    r = polrig.Rig()
    with pytest.raises(KeyError, match="unknown rig key 'nope'"):
        r["nope"]
    with pytest.raises(polrig.RigError, match="unknown key 'nope'"):
        r["nope"] = 1
    assert "eccentricity.L_IS" in r and "nope" not in r
    assert "sky.p_max" not in r  # a key, but not one a cos4 rig's source reads


def test_from_dict_nested_and_flat_agree():
    a = polrig.Rig.from_dict({"eccentricity": {"L_S": 0.07, "alpha_S": 30}, "seed": 5})
    b = polrig.Rig.from_dict({"eccentricity.L_S": 0.07, "eccentricity.alpha_S": 30, "seed": 5})
    assert a.to_yaml() == b.to_yaml()
    assert a["eccentricity.L_S"] == 0.07 and a["seed"] == 5
    with pytest.raises(TypeError, match="eccentricity.L_S"):
        polrig.Rig.from_dict({"eccentricity.L_S": object()})


def test_update_is_all_or_nothing():
    r = polrig.Rig()
    before = r.to_yaml()
    with pytest.raises(polrig.RigError):
        r.update({"eccentricity.L_S": 0.2, "eccentricity.L_IS": -5})
    assert r.to_yaml() == before
    r.update({"eccentricity.L_S": 0.2, "eccentricity.L_IS": 0.5})
    assert (r["eccentricity.L_S"], r["eccentricity.L_IS"]) == (0.2, 0.5)


def test_a_pickled_rig_loads_in_another_folder(tmp_path, monkeypatch):
    traced = polrig.Rig.load(str(ROOT / "rigs" / "wang2019-indoor-traced.yaml"))
    data = pickle.dumps(traced)
    monkeypatch.chdir(tmp_path)  # the scene file is named relative to the rig file
    assert pickle.loads(data).to_yaml() == traced.to_yaml()


def test_copies_and_pickles_are_independent():
    r = polrig.Rig.load(INDOOR, set={"eccentricity.L_S": 0.05})
    for c in (r.copy(), copy.copy(r), copy.deepcopy(r), pickle.loads(pickle.dumps(r))):
        assert c.to_yaml() == r.to_yaml()
        c["eccentricity.L_S"] = 0.5
        assert r["eccentricity.L_S"] == 0.05


def test_rig_keys_is_the_cli_table():
    keys = polrig.rig_keys()
    table = run_cli("rig", "keys").stdout.splitlines()[2:]
    assert [k["path"] for k in keys] == [row.split("|")[1].strip().strip("`") for row in table]
    k = next(k for k in keys if k["path"] == "eccentricity.L_IS")
    assert k["unit"] == "mm" and k["kind"] == "real" and "cs" in k["read_by"]


def test_a_sky_rig_lists_only_the_keys_its_source_reads():
    sky = polrig.Rig.load(str(ROOT / "rigs" / "wang2019-outdoor1.yaml"))
    assert sky["source.model"] == "sky"
    assert "sky.p_max" in sky.keys() and "sky.p_max" not in polrig.Rig().keys()
