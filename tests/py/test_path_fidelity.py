"""pyscripts/trueaniso/analysis/path_fidelity.py: reversals counted on a hand-made table."""
import pytest

from trueaniso.analysis import path_fidelity


def _row(state, b, sz, probe, E, sx, sy, szz, zm="5.9", gap="6.0"):
    return dict(state=state, b=str(b), sigma_z_goal=str(sz), probe=probe, E=str(E), sigma_x=str(sx),
                sigma_y=str(sy), sigma_z=str(szz), Zm=zm, **{"Zm_gap1e-3": gap}, probe_wall_time="1",
                state_wall_time="2")


def test_reversals_on_a_hand_made_path():
    """b = 0 in compression: isotropic 1, then 2 and 3 by distance. E_z rises then falls while
    sigma_z rises (one reversal, 2 -> 3); E_x falls while sigma_x falls (no reversal); E_y falls
    with sigma_y moving 0.3 kPa (below the 0.5 kPa threshold: none)."""
    rows = []
    for st, sz, ez, ex, ey, sx, sy in (("1", 100e3, 300, 300, 300, 100e3, 100e3),
                                      ("3", 140e3, 315, 280, 295, 80e3, 100.3e3),
                                      ("2", 120e3, 320, 290, 299, 90e3, 100e3)):
        for ax, E in (("z", ez), ("x", ex), ("y", ey)):
            rows.append(_row(st, 0.0, sz, ax, E * 1e6, sx, sy, sz))
    rows.append(_row("2", 0.0, 120e3, "yz", "", 90e3, 100e3, 120e3))  # shear probes are skipped
    found = path_fidelity.reversals(rows)
    assert [(a, b, ax) for a, b, ax, *_ in found] == [("2", "3", "z")]
    s = path_fidelity.summary(rows)
    assert s["states"] == 3 and s["reversals"] == 1 and s["Zm"] == (5.9, 5.9) and s["wall_time"] == 10 + 6  # 10 probes, 3 states


def test_zeta_trend_by_hand():
    """Spearman's rho of per-state zeta with Zm, and the high-Zm and low-Zm means, on five states."""
    import numpy as np
    from trueaniso.analysis import chain
    tab = dict(state=["1", "2", "3", "4", "5"], Zm=np.array([5.95, 5.94, 5.80, 5.70, 5.60]))
    zetas = {"2": 0.40, "3": 0.30, "4": 0.10, "5": 0.05}  # state 1 is the reference: no zeta
    t = chain.zeta_trend(tab, zetas)
    assert t["rho"] == 1.0  # zeta rises with Zm at every step
    assert (t["high"], t["n_high"]) == (0.40, 1)  # within 0.02 of 5.95: state 2 (1 has none)
    assert (t["low"], t["n_low"]) == (0.05, 1)  # below 5.60 + 0.2 * 0.35 = 5.67: state 5
    zetas["3"] = None  # a state whose contrast does not depend on zeta is left out
    assert chain.zeta_trend(tab, zetas)["rho"] == 1.0


def test_table_row_of_a_study_directory(tmp_path):
    """study_row on a study directory made of eight states of the committed 4000-sphere table and
    a metadata.json: each column against the same number computed another way."""
    import csv
    import json
    import os
    from conftest import REPO
    from trueaniso.analysis import zeta_contrast
    data = os.path.join(REPO, "docs", "data", "table-c1-spheres-4000.csv")
    keep = ("1", "5", "9", "13", "21", "25", "29", "37")
    with open(data, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["state"] in keep]
    with open(tmp_path / "probes.csv", "w", newline="") as f:
        w = csv.DictWriter(f, list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    material = dict(shear_modulus=18e9, poisson=0.15, density=2500.0, friction=0.5)
    meta = dict(fingerprint=dict(threads=2, state=dict(rolling_stiffness=0.0, rolling_friction=0.0)),
                specimen=dict(seed=1, material=material, summary=dict(n=4000)))
    (tmp_path / "metadata.json").write_text(json.dumps(meta))
    r = path_fidelity.study_row(str(tmp_path))
    zm = [float(x["Zm"]) for x in rows]
    assert r["states"] == 8 and r["Zm"] == (min(zm), max(zm)) and (r["n"], r["seed"], r["rolling"]) == (4000, 1, (0, 0))
    assert r["reversals"] == len(path_fidelity.reversals(rows))
    assert r["zeta"] == zeta_contrast.fit(str(tmp_path / "probes.csv"), 18e9, 0.15)["zeta"]
    per_state = {x["state"]: int(x["state_steps"]) for x in rows}
    assert r["steps"] == sum(int(x["probe_steps"]) for x in rows) + sum(per_state.values())
    e1 = [float(x["E"]) for x in rows if x["state"] == "1" and x["probe"] in ("x", "y", "z")]
    assert abs(r["E_iso"] - sum(e1) / 3) < 1e-6 * r["E_iso"]
    line = path_fidelity.markdown_table([r]).splitlines()[2]
    assert line.startswith("| 4000 | 1 | off | 8 | %.3f-%.3f" % (min(zm), max(zm))) and "(2)" in line
    (tmp_path / "metadata.json").unlink()
    with pytest.raises(path_fidelity.ResultsError, match="metadata.json"):
        path_fidelity.study_row(str(tmp_path))


def test_help_and_bad_gap_tolerances(tmp_path, capsys):
    """--help is help, not a missing probe table, and a bad --gaps list is one line, not a traceback."""
    assert path_fidelity.main(["--help"]) == 0
    assert "--table" in capsys.readouterr().out
    for args in (["--gaps"], ["--gaps", "x", str(tmp_path)], ["--gaps", "1e-4"], ["--gaps", "0,1e-3", str(tmp_path)],
                 ["--gaps", "nan", str(tmp_path)]):
        assert path_fidelity.main(args) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error: --gaps takes gap tolerances"), (args, err)
