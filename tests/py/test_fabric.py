"""Fabric measures and the micromechanical prediction as seen from Python: against a numpy brute
force computed from positions alone, by hand on two clumps, and side by side with YADE."""
import math

import numpy as np
import pytest

from trueaniso import dem, engines as E, fabric


def _random_network(n, phi, seed, dimers=False):
    """n spheres (or dimers) at random at solid fraction phi, overlaps allowed, forces evaluated."""
    rng = np.random.default_rng(seed)
    r = 1e-4 * (0.8 + 0.4 * rng.random(n))
    vol = np.sum(4.0 / 3.0 * math.pi * r ** 3) * (1.8 if dimers else 1.0)
    side = (vol / phi) ** (1.0 / 3.0)
    s = E.Scene()
    s.cell_size = s.cell_ref_size = [side] * 3
    pos = rng.random((n, 3)) * side
    if not dimers:
        s.add_spheres(pos, r)
    else:
        for k in range(n):
            q = rng.normal(size=4)
            radii = [r[k], 0.8 * r[k]]
            m = s.density * 4.0 / 3.0 * math.pi * sum(x ** 3 for x in radii)
            s.add_clump(pos[k], q / np.linalg.norm(q), [[-0.5 * r[k], 0, 0], [0.6 * r[k], 0, 0]], radii, m,
                        [0.4 * m * r[k] ** 2] * 3)
    _evaluate(s)
    return s


def _evaluate(s):
    sim = E.Simulation(s)
    sim.add(E.ContactDetection())
    sim.add(E.ContactForces())
    sim.run(1)


def _union_volumes(s):
    """Solid volume of each body in closed form: a ball, or two overlapping balls minus their lens
    (two spherical caps cut by the radical plane); independent of the engines' CGAL templates."""
    mb, rad, off = s.member_begin, s.radii, s.member_offsets
    out = []
    for b in range(s.num_bodies):
        r = rad[mb[b]:mb[b + 1]]
        if len(r) == 1:
            out.append(4 / 3 * math.pi * r[0] ** 3)
            continue
        assert len(r) == 2
        R, q = r
        d = np.linalg.norm(off[mb[b] + 1] - off[mb[b]])
        h1 = (q - R + d) * (q + R - d) / (2 * d)
        h2 = (R - q + d) * (q + R - d) / (2 * d)
        lens = math.pi / 3 * (h1 * h1 * (3 * R - h1) + h2 * h2 * (3 * q - h2))
        out.append(4 / 3 * math.pi * (R ** 3 + q ** 3) - lens)
    return np.array(out)


def _brute_force(s):
    """Every touching member pair of different bodies from positions (minimum image), Hertz force
    N = (4/3) E* sqrt(rbar/2) delta^1.5, then Eqs. (14)-(16), (33), (34), (36) with numpy."""
    h = s.cell_size
    p, rad, body = s.member_positions, s.radii, s.member_body
    i, j = np.triu_indices(len(rad), 1)
    keep = body[i] != body[j]
    i, j = i[keep], j[keep]
    d = p[j] - p[i]
    image = -h * np.round(d / h)
    d = d + image
    dist = np.linalg.norm(d, axis=1)
    delta = rad[i] + rad[j] - dist
    t = delta > 0
    i, j, d, dist, delta, image = i[t], j[t], d[t], dist[t], delta[t], image[t]
    n = d / dist[:, None]
    L = s.positions[body[j]] + image - s.positions[body[i]]
    rbar = 2 * rad[i] * rad[j] / (rad[i] + rad[j])
    estar = s.shear_modulus / (1 - s.poisson)
    N = 4.0 / 3.0 * estar * np.sqrt(rbar / 2) * delta ** 1.5
    w = np.cbrt(rbar * N)
    nc = len(N)
    per = np.bincount(np.concatenate([body[i], body[j]]), minlength=s.num_bodies)
    np0, np1 = np.sum(per == 0), np.sum(per == 1)
    zm = (2 * nc - np1) / (s.num_bodies - np0 - np1)
    V = np.prod(h)
    vs = np.sum(_union_volumes(s))  # the solid is the union of each body's members (overlap once)
    e = (V - vs) / vs
    r3 = 3 * vs / (4 * math.pi * s.num_bodies)  # equal-volume radius, mean of r^3
    return dict(Zm=zm, Nc=nc, Np0=np0, Np1=np1, R=n.T @ n / nc, H=L.T @ L / nc, B=(w[:, None] * L).T @ L / nc,
                M=np.einsum("c,ci,cj,ck,cl->ijkl", w, L, n, L, n) / nc,
                NcV_eq36=3 * zm / (8 * math.pi * (1 + e) * r3), NcV_count=nc / V, e=e, mean_N=N.mean())


def _rel(a, b):
    return np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b))


@pytest.mark.parametrize("dimers", [False, True])
def test_fabric_equals_numpy_brute_force(dimers):
    s = _random_network(300, 0.6, 7, dimers)
    f, ref = fabric.fabric(s), _brute_force(s)
    assert f["Nc"] == ref["Nc"] > 300
    assert (f["Np0"], f["Np1"]) == (ref["Np0"], ref["Np1"])
    assert f["Np1"] > 0  # Eq. (14)'s correction is exercised
    # sums of ~1e3 products of doubles, overlaps computed the same way: 1e-12 relative
    for key in ("R", "H", "B", "M"):
        assert _rel(f[key], ref[key]) < 1e-12, key
    for key in ("Zm", "NcV_count", "mean_N"):
        assert f[key] == pytest.approx(ref[key], rel=1e-12), key
    # e and Eq. (36) read the solid volume: exact for spheres; for dimers the engines' CGAL union
    # (relative error <= 5e-5, tests/cpp/test_clump.cpp), so e to (1 + e)/e x 5e-5 = 1e-4 here.
    for key in ("NcV_eq36", "e"):
        assert f[key] == pytest.approx(ref[key], rel=1e-4 if dimers else 1e-12), key
    assert np.trace(f["R"]) == pytest.approx(1.0, abs=1e-15)
    # Sum_j M_ijkj = B_ik (n is a unit vector) and M_ijkl = M_klij, checked on the numpy layout
    assert _rel(np.einsum("ijkj->ik", f["M"]), f["B"]) < 1e-14
    assert np.array_equal(f["M"], f["M"].transpose(2, 3, 0, 1))


def test_two_clumps_by_hand():
    """Two dimers (members at +-d), the second shifted by (0, 2r - delta, 0): two member contacts
    with n = (0, 1, 0) and L = (0, 2r - delta, 0); nothing else touches. Nc = 2 (each member
    contact counts), Np = 2, Zm = 2 Nc / Np = 2; R = e_y e_y, H = L L, B = w L L with
    w = (r N)^(1/3) (rbar = r for equal members), M_yyyy = w Ly^2 and no other M component."""
    s = E.Scene()
    s.cell_size = s.cell_ref_size = [2e-3] * 3
    r, d, delta = 1e-4, 0.8e-4, 3e-7
    m = s.density * 2 * 4.0 / 3.0 * math.pi * r ** 3
    for y in (1e-3, 1e-3 + 2 * r - delta):
        s.add_clump([1e-3, y, 1e-3], [1, 0, 0, 0], [[-d, 0, 0], [d, 0, 0]], [r, r], m, [1e-12, 2e-12, 2e-12])
    _evaluate(s)
    f = fabric.fabric(s)
    assert (f["Nc"], f["Np"], f["Np0"], f["Np1"], f["Zm"]) == (2, 2, 0, 0, 2.0)
    Ly = 2 * r - delta
    N = 4.0 / 3.0 * s.shear_modulus / (1 - s.poisson) * math.sqrt(r / 2) * delta ** 1.5
    w = (r * N) ** (1.0 / 3.0)
    ey = np.outer([0, 1, 0], [0, 1, 0])
    assert _rel(f["R"], ey) < 1e-15
    assert _rel(f["H"], Ly ** 2 * ey) < 1e-12
    # delta = 2r - |distance| is known to the rounding of a difference of ~2e-4: ~1e-12 in N
    assert _rel(f["B"], w * Ly ** 2 * ey) < 1e-11
    M = np.zeros((3, 3, 3, 3))
    M[1, 1, 1, 1] = w * Ly ** 2
    assert _rel(f["M"], M) < 1e-11
    assert f["mean_N"] == pytest.approx(N, rel=3e-11)
    # Eq. (36) with the clumps' equal-volume radius r_eq^3 = 3 m / (4 pi rho) = 2 r^3
    e = (8e-9 - 2 * m / s.density) / (2 * m / s.density)
    assert f["NcV_eq36"] == pytest.approx(3 * 2.0 / (8 * math.pi * (1 + e) * 2 * r ** 3), rel=1e-13)


def test_micromechanics_layout_follows_eq37():
    """engines.micromechanics reads B[i,k] and M[i,j,k,l] and returns C[i,j,k,l] as Eq. (37) says
    (checked with numpy's einsum on arbitrary tensors), and Appendix A's symmetrisation."""
    rng = np.random.default_rng(3)
    B, M = rng.random((3, 3)), rng.random((3, 3, 3, 3))
    ncv, Cn, Cs, zeta = 2.0, 5.0, 3.0, 0.4
    p = E.micromechanics(B, M, ncv, Cn, Cs, zeta)
    C = ncv * (zeta * Cs * np.einsum("ik,jl->ijkl", B, np.eye(3)) + (Cn - zeta * Cs) * M)
    assert _rel(p["C"], C) < 1e-15
    V = p["voigt"]
    assert V[0, 1] == pytest.approx(0.5 * (C[0, 0, 1, 1] + C[1, 1, 0, 0]), rel=1e-15)  # A4
    assert V[3, 3] == pytest.approx(0.5 * (C[1, 2, 1, 2] + C[2, 1, 2, 1]), rel=1e-15)  # A7
    S = np.linalg.inv(V)
    assert p["E"] == pytest.approx(1 / np.diag(S)[:3], rel=1e-12)
    assert p["nu"][2, 1] == pytest.approx(-S[1, 2] / S[2, 2], rel=1e-12)  # nu_zy, Eq. (42) corrected


def test_fabric_row_columns_are_the_measures():
    s = _random_network(200, 0.6, 11)
    f, row = fabric.fabric(s), fabric.fabric_row(s, zeta=0.552)
    p = fabric.prediction(s, zeta=0.552)
    assert row["R_xy"] == f["R"][0, 1] and row["B_zz"] == f["B"][2, 2] and row["H_yz"] == f["H"][1, 2]
    assert row["M_yzyz"] == f["M"][1, 2, 1, 2] and row["M_zzxx"] == f["M"][2, 2, 0, 0]
    assert len([k for k in row if k.startswith("M_")]) == 15  # the components of A1-A9
    assert row["mic_E_y"] == p["E"][1] and row["mic_nu_zx"] == p["nu"][2, 0] and row["mic_G_xy"] == p["G"][2]
    assert row["mic_zeta"] == 0.552 and row["Zm"] == f["Zm"] and row["NcV_eq36"] == f["NcV_eq36"]
    # Nc/V only scales the moduli: the counted density gives E in the ratio of the densities
    pc = fabric.prediction(s, zeta=0.552, density="count")
    assert pc["E"] == pytest.approx(p["E"] * f["NcV_count"] / f["NcV_eq36"], rel=1e-13)
    assert pc["nu"][0, 1] == pytest.approx(p["nu"][0, 1], rel=1e-13)


def test_fabric_row_has_the_gap_tolerant_count():
    """Zm_gap1e-3 beside Zm: the engine's count at the default tolerance; its column
    name follows the tolerance; a brute-force count of pairs with gap < tol (r1 + r2) gives its
    N_c; tolerance 0 gives back Zm; a tolerance the skin cannot hold is refused."""
    s = _random_network(200, 0.6, 11)
    row = fabric.fabric_row(s)
    assert E.GAP_TOLERANCE == 1e-3 and fabric.gap_column(1e-3) == "Zm_gap1e-3"
    assert fabric.gap_column(2.5e-2) == "Zm_gap2.5e-2"
    assert row["Zm_gap1e-3"] == E.coordination_gap(s)["Zm"] and row["Zm_gap1e-3"] >= row["Zm"]
    assert E.coordination_gap(s, 0.0)["Zm"] == row["Zm"]
    pos, r, side = np.asarray(s.positions), np.asarray(s.radii), s.cell_size[0]
    for tol in (1e-3, 2e-2):
        d = pos[None, :, :] - pos[:, None, :]
        d -= side * np.round(d / side)
        rs = r[:, None] + r[None, :]
        near = np.triu(np.linalg.norm(d, axis=2) - rs < tol * rs, 1)
        assert fabric.gap_columns(s, tol)["Nc" + fabric.gap_column(tol)[2:]] == int(near.sum())
    with pytest.raises(ValueError, match="gap tolerance"):
        E.coordination_gap(s, 0.1)


def test_recorder_samples_the_running_network():
    """Records at steps 0, 5, 10 of an 11-step run with the integrator moving the bodies; the
    last record equals the fabric of the last force evaluation, and the network did change."""
    s = _random_network(300, 0.6, 5)
    rec = fabric.recorder(every=5)
    chain = dem.Chain(s, damping=0.0, controllers=[rec])
    s.dt = 0.5 * chain.timestep.max_dt
    s.step = 0
    chain.run(11)
    h = fabric.history(rec)
    assert list(h["step"]) == [0, 5, 10] and rec.size == 3
    assert h["M"].shape == (3, 3, 3, 3, 3) and h["R"].shape == (3, 3, 3)
    f = fabric.fabric(s)
    for key in ("R", "H", "B", "M"):
        assert np.array_equal(h[key][-1], f[key]), key
    assert h["Zm"][-1] == f["Zm"] and h["NcV_eq36"][-1] == f["NcV_eq36"]
    assert np.max(np.abs(h["B"][-1] - h["B"][0])) > 1e-6 * np.max(np.abs(h["B"][0]))
    rows = fabric.history_rows(rec, s.shear_modulus, s.poisson)
    assert rows[-1]["step"] == 10 and rows[-1]["mic_E_x"] == pytest.approx(fabric.prediction(s)["E"][0], rel=1e-14)


def test_bad_input_gets_a_clear_error():
    s = _random_network(50, 0.6, 1)
    with pytest.raises(ValueError, match="zeta"):
        fabric.fabric_row(s, zeta=E.ZETA_RANGE[1] * 1.1)
    with pytest.raises(ValueError, match="zeta"):
        fabric.prediction(s, zeta=-0.1)
    with pytest.raises(ValueError, match="density"):
        fabric.prediction(s, density="eq35")
    with pytest.raises(ValueError, match="every"):
        fabric.recorder(every=0)
    s.positions = s.positions  # bodies "moved": the contacts no longer describe this configuration
    with pytest.raises(ValueError, match="ContactDetection"):
        fabric.fabric(s)
    with pytest.raises(ValueError, match="recorded"):
        fabric.recorder().last()


def test_fabric_of_yade_packing_matches_yade(yade_json):
    r = yade_json("peer_fabric", "300")
    ours, py = r["ours"], r["python"]
    assert r["n"] == 300 and ours["Nc"] == py["Nc"] == r["yade_real_interactions"] > 500
    assert ours["Np0"] + ours["Np1"] > 0  # skipFree has something to skip
    # Eq. (14) is Thornton's Zm, which YADE's avgNumInteractions(skipFree=True) computes: same counts
    assert ours["Zm"] == r["yade_Zm"]
    # fabricTensor()[0] is the full Satake tensor (1/Nc) sum n n over real interactions (not its
    # deviator; the strong/weak split only with splitTensor=True): the same normals, 1e-14
    assert _rel(ours["R"], r["yade_R"]) < 1e-14
    porosity = r["yade_porosity"]
    assert ours["e"] == pytest.approx(porosity / (1 - porosity), rel=1e-12)
    # the Python code over O.interactions: YADE's normals and forces vs ours recomputed from the
    # same positions (the forces agree to ~1e-15 here; 1e-10 leaves room for tiny overlaps)
    for key in ("R", "H", "B", "M"):
        assert _rel(ours[key], py[key]) < 1e-10, key
    for key in ("Zm", "NcV_eq36", "NcV_count", "mean_N"):
        assert ours[key] == pytest.approx(py[key], rel=1e-10), key
