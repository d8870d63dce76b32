"""Clump shapes of the two clump assemblies and the orientation distributions of their recipes.

The paper shows its clump shapes only in Fig. 1; the shapes here are our choice, with the reasons
and the alternatives measured in docs/specimens.md. A shape is given as member centres and radii
in units of the largest member radius; its mass properties (the union of the balls, overlaps
counted once) come from the C++ ClumpTemplate (CGAL), computed once per process and shape.
A clump's size in a size distribution is the diameter of the sphere of equal volume (PFC's
convention for clump templates), so the template is scaled to unit equivalent diameter here.
"""
import math

import numpy as np

from . import engines

# name: (centres, radii), units of the largest member radius. The template's axis 0 (smallest
# principal moment) is the long axis of these elongated shapes.
SHAPES = {
    # two equal balls, centres one radius apart: aspect ratio (2r + r)/2r = 1.5
    "dimer-1.5": ([[0, 0, 0], [1.0, 0, 0]], [1.0, 1.0]),
    # the same at aspect ratio 1.3 and 1.7
    "dimer-1.3": ([[0, 0, 0], [0.6, 0, 0]], [1.0, 1.0]),
    "dimer-1.7": ([[0, 0, 0], [1.4, 0, 0]], [1.0, 1.0]),
    # three equal balls in a row, neighbours one radius apart: aspect ratio 2
    "trimer-2.0": ([[-1.0, 0, 0], [0, 0, 0], [1.0, 0, 0]], [1.0, 1.0, 1.0]),
    # the same with neighbours 0.8 radius apart: aspect ratio 1.8
    "trimer-1.8": ([[-0.8, 0, 0], [0, 0, 0], [0.8, 0, 0]], [1.0, 1.0, 1.0]),
    # five equal balls in a row, neighbours half a radius apart: the trimer's length and aspect
    # ratio 2 with shallower waists, nearer a spherocylinder (docs/specimens.md, clump1's void ratio)
    "pentamer-2.0": ([[-1.0, 0, 0], [-0.5, 0, 0], [0, 0, 0], [0.5, 0, 0], [1.0, 0, 0]], [1.0] * 5),
}

_cache = {}


def template(shape):
    """The ClumpTemplate of a named shape scaled to an equivalent diameter of 1 (m)."""
    if shape not in SHAPES:
        raise ValueError("unknown clump shape %r (available: %s)" % (shape, ", ".join(sorted(SHAPES))))
    if shape not in _cache:
        centres, radii = SHAPES[shape]
        t = engines.ClumpTemplate(np.array(centres, dtype=float), np.array(radii, dtype=float))
        _cache[shape] = t.scaled(1.0 / t.equivalent_diameter)
    return _cache[shape]


def aspect_ratio(t):
    """Length along the long axis (template axis 0) over the width across it."""
    off, r = t.offsets, t.radii
    length = np.max(off[:, 0] + r) - np.min(off[:, 0] - r)
    width = 2.0 * max(np.max(np.hypot(off[:, 1], off[:, 2]) + r), 0.0)
    return float(length / width)


def rotation_matrix(q):
    """Rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def rotated(points, R):
    """points (n, 3) turned by the rotation matrix R: points @ R.T, as sums of products in a fixed
    order. A matrix product would go to BLAS, whose kernel (chosen by processor, or by
    OPENBLAS_CORETYPE) sets the last bits, and these positions decide a packing's bits."""
    p = np.asarray(points, dtype=float)
    return p[:, 0:1] * R[:, 0] + p[:, 1:2] * R[:, 1] + p[:, 2:3] * R[:, 2]


def _unit(v):
    """v / |v| for a 3-vector without BLAS (np.linalg.norm of a vector is a BLAS dot)."""
    return v / math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


def quaternion_product(a, b):
    """a b for quaternions (w, x, y, z): the rotation b, then a."""
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def quaternion_from_matrix(R):
    """(w, x, y, z) of a rotation matrix (Shepperd's method, stable for every rotation)."""
    t = np.trace(R)
    if t > 0:
        s = 2.0 * math.sqrt(1.0 + t)
        return np.array([0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s])
    i = int(np.argmax(np.diag(R)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * math.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k])
    q = np.empty(4)
    q[0] = (R[k, j] - R[j, k]) / s
    q[1 + i] = 0.25 * s
    q[1 + j] = (R[j, i] + R[i, j]) / s
    q[1 + k] = (R[k, i] + R[i, k]) / s
    return q


def long_axes(n, rng, weights):
    r"""n unit vectors from the angular central Gaussian distribution with covariance
    $\operatorname{diag}(w_x^2, w_y^2, w_z^2)$: $u = g/\lVert g \rVert$ with $g = (w_x g_1, w_y g_2, w_z g_3)$,
    $g_i$ standard normal. Equal weights give isotropic directions; $w_z > w_x = w_y$ favours the vertical, $w_z < w_x = w_y$
    the horizontal plane, and the distribution is then transversely isotropic about z."""
    w = np.asarray(weights, dtype=float)
    if w.shape != (3,) or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ValueError("orientation weights must be three finite numbers > 0")
    g = rng.standard_normal((n, 3)) * w
    return g / np.sqrt(g[:, 0] * g[:, 0] + g[:, 1] * g[:, 1] + g[:, 2] * g[:, 2])[:, None]


def orientations(n, rng, weights):
    """Quaternions (n, 4) that turn the template's long axis (axis 0) onto long_axes(...), with a
    uniform random spin about it."""
    u = long_axes(n, rng, weights)
    spin = rng.random(n) * 2.0 * math.pi
    out = np.empty((n, 4))
    for k in range(n):
        a = u[k]
        # any unit vector normal to a, then turned by the spin about a
        helper = np.array([0.0, 0.0, 1.0]) if abs(a[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
        b = _unit(np.cross(a, helper))
        c = np.cross(a, b)
        b, c = math.cos(spin[k]) * b + math.sin(spin[k]) * c, -math.sin(spin[k]) * b + math.cos(spin[k]) * c
        out[k] = quaternion_from_matrix(np.column_stack([a, b, c]))
    return out


def long_axis_fabric(scene):
    """<u u> of the clumps' long axes (template axis 0 in the world): the orientation fabric of the
    particles themselves, which the preparation sets and the contact fabric follows."""
    multi = np.diff(scene.member_begin) > 1
    u = np.array([rotation_matrix(q)[:, 0] for q in scene.orientations[multi]]).reshape(-1, 3)
    return u.T @ u / max(len(u), 1)
