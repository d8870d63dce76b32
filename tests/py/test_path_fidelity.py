"""analysis/path_fidelity.py: reversals counted on a hand-made table (issue 14)."""
from analysis import path_fidelity


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
