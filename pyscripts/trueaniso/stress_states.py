"""The stress states of the paper: Table C1, Eqs. (8)-(9) and the loading paths' mean stress.

Data and closed forms only, with no compiled module: the engines take a state as (b, sigma_z, p)
(engines.true_triaxial_stresses is Eq. 9 in C++, which the servo holds), and the readers of result
files (trueaniso.analysis) check a row's stresses against its state's definition with these, on a
machine without the build too. triaxial.py re-exports every name.
"""


# Table C1: (ID, sigma_x, sigma_y, sigma_z, q) in kPa, as printed (rounded to 0.1 kPa).
TABLE_C1 = [
    (1, 100, 100, 100, 0), (2, 95, 95, 110, 15), (3, 90, 90, 120, 30), (4, 85, 85, 130, 45),
    (5, 80, 80, 140, 60), (6, 105, 105, 90, -15), (7, 110, 110, 80, -30), (8, 115, 115, 70, -45),
    (9, 120, 120, 60, -60), (10, 97.1, 92.9, 110, 15.5), (11, 94.3, 85.7, 120, 30.9),
    (12, 91.4, 78.6, 130, 46.4), (13, 88.6, 71.4, 140, 61.8), (14, 102.9, 107.1, 90, -15.5),
    (15, 105.7, 114.3, 80, -30.9), (16, 108.6, 121.4, 70, -46.4), (17, 111.4, 128.6, 60, -61.8),
    (18, 100, 90, 110, 17.3), (19, 100, 80, 120, 34.6), (20, 100, 70, 130, 52.0),
    (21, 100, 60, 140, 69.3), (22, 100, 110, 90, -17.3), (23, 100, 120, 80, -34.6),
    (24, 100, 130, 70, -52.0), (25, 100, 140, 60, -69.3), (26, 104, 86, 110, 21.6),
    (27, 108, 72, 120, 43.3), (28, 112, 58, 130, 64.9), (29, 96, 114, 90, -21.6),
    (30, 92, 128, 80, -43.3), (31, 88, 142, 70, -64.9), (32, 105, 90, 105, 15),
    (33, 110, 80, 110, 30), (34, 115, 70, 115, 45), (35, 120, 60, 120, 60),
    (36, 95, 110, 95, -15), (37, 90, 120, 90, -30), (38, 85, 130, 85, -45), (39, 80, 140, 80, -60),
]


def b_of(sx, sy, sz):
    r"""b of Eq. (8) from the three principal stresses, $(\sigma_x - \sigma_y)/(\sigma_z - \sigma_y)$.

    The isotropic state has no b: 0 is returned (every path of Table C1 passes through it).

    Example:
        >>> from trueaniso import triaxial
        >>> triaxial.b_of(100e3, 60e3, 140e3)
        0.5
    """
    return 0.0 if abs(sz - sy) < 1e-12 else (sx - sy) / (sz - sy)


def table_c1_states():
    """The 39 states of the paper's Table C1, b rounded to the paper's five values (0, 0.25, 0.5, 0.75, 1).

    Returns:
        list: (id, b, sigma_z in Pa) per state, by id.

    Example:
        >>> from trueaniso import triaxial
        >>> triaxial.table_c1_states()[20]
        (21, 0.5, 140000.0)
    """
    out = []
    for i, sx, sy, sz, _ in TABLE_C1:
        b = min((0.0, 0.25, 0.5, 0.75, 1.0), key=lambda v: abs(v - b_of(sx, sy, sz)))
        out.append((i, b, sz * 1e3))
    return out


# Loading paths a study can follow (run_states.py --path). "true-triaxial": the paper's Table C1
# paths, constant b and p = 100 kPa (Eqs. 8-9). "cross-anisotropic": its Fig. 16 (after Zhou et
# al. 2026c), sigma_h = sigma_x = sigma_y held at SIGMA_H while sigma_v = sigma_z varies.
PATHS = ("true-triaxial", "cross-anisotropic")
SIGMA_H = 100e3


def path_mean_stress(path, b, sigma_z):
    r"""The mean stress p of the state (b, sigma_z) on a path: 100 kPa on the true-triaxial paths;
    on the cross-anisotropic path (b = 0 there) $(2\sigma_h + \sigma_v)/3$, which makes Eq. (9)
    give $\sigma_x = \sigma_y = \sigma_h$ for any $\sigma_v$, so the servo's straight stress path from
    the isotropic state keeps $\sigma_h$ at 100 kPa all the way."""
    if path == "true-triaxial":
        return 100e3
    if path == "cross-anisotropic":
        return (2.0 * SIGMA_H + sigma_z) / 3.0
    raise ValueError("unknown path %r: the paths are %s" % (path, ", ".join(PATHS)))


def principal_stresses(b, sigma_z, p=100e3):
    r"""Eq. (9): ($\sigma_x$, $\sigma_y$, $\sigma_z$) of constant b (Eq. 8) and mean stress p (Pa)."""
    sx = ((2.0 * b - 1.0) * sigma_z + 3.0 * p * (1.0 - b)) / (2.0 - b)
    sy = (3.0 * p - (b + 1.0) * sigma_z) / (2.0 - b)
    return sx, sy, sigma_z


def path_principal_stresses(path, b, sigma_z):
    r"""$\sigma_x$, $\sigma_y$, $\sigma_z$ (Pa) of the state on its path (Eq. 9 at the path's mean stress)."""
    return principal_stresses(b, sigma_z, path_mean_stress(path, b, sigma_z))


def defined_by_id(sid):
    """(b, sigma_z) that a state's id itself says, or None: a Table C1 number (1-39, on the
    true-triaxial path), 'b<b>_sz<sigma_z in Pa>' (study.state_id) or 'sv<sigma_v in kPa>' (the
    cross-anisotropic path, b = 0). Other ids (a study's own names) say nothing."""
    sid = str(sid)
    if sid.isdigit():
        found = [(b, sz) for i, b, sz in table_c1_states() if i == int(sid)]
        return found[0] if found else None
    try:
        if sid.startswith("sv"):
            return 0.0, float(sid[2:]) * 1e3
        if sid.startswith("b") and "_sz" in sid:
            b, sz = sid[1:].split("_sz")
            return float(b), float(sz)
    except ValueError:
        return None
    return None
