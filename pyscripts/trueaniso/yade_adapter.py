"""Our servo and probe inside a YADE simulation (yade-double), with YADE's own dynamics and its
Hertz-Mindlin law: a thin adapter called every step by a PyRunner (`attach`, `run_until_done`).

The adapter measures what our controllers read (YADE's whole getStress tensor with our sign, the
cell's deformation gradient since the adapter was attached, YADE's unbalanced force), calls the
controller's C++ update() for the six strain rates, and sets O.cell.velGrad to their symmetric
tensor (YADE applies a new velGrad from the next step on). The stiffness estimate that scales the
gain is our affine estimate of the imported scene (trueaniso.engines.cell_stiffness, six
components), constant over the small strains of a state or a probe.
"""
import math

import numpy as np

__all__ = ["attach", "detach", "run_until_done", "set_friction"]

_ACTIVE = {}


def _matrix(m):
    return np.array([[m[i][j] for j in range(3)] for i in range(3)])


class CellAdapter:
    """The PyRunner's callable of `attach`: measures YADE's cell, updates the controller, sets velGrad."""

    def __init__(self, controller, stiffness, O):
        self.controller = controller
        self.stiffness = np.asarray(stiffness, dtype=float)
        self.O = O
        self.ref_inverse = np.linalg.inv(_matrix(O.cell.hSize))
        self.calls = 0
        self.was_done = controller.done

    def measure(self):
        from yade import utils
        O = self.O
        stress = -_matrix(utils.getStress())
        deformation = _matrix(O.cell.hSize) @ self.ref_inverse
        unbalanced = utils.unbalancedForce()
        if not math.isfinite(unbalanced):
            unbalanced = 1.0
        return stress, deformation, unbalanced

    def __call__(self):
        from yade import Matrix3
        from . import engines
        stress, deformation, unbalanced = self.measure()
        rates = self.controller.update(stress, deformation, self.stiffness, unbalanced, self.O.dt)
        L = engines.velocity_gradient(rates)
        self.O.cell.velGrad = Matrix3(*[float(v) for v in L.ravel()])
        self.calls += 1
        # Pause once, when the controller gets done: that is how run_until_done's O.run returns.
        # Pausing at every call after it would make any later O.run(N) of the scene stop after one
        # step, without a word, while the finished controller stays attached.
        if self.controller.done and not self.was_done:
            self.O.pause()
        self.was_done = self.controller.done


DEFAULT_LABEL = "trueanisoController"


def attach(controller, stiffness, O=None, label=DEFAULT_LABEL):
    """Drive YADE's cell with one of our controllers: a PyRunner calling it every step, before NewtonIntegrator.

    Every step the adapter measures what the controller reads (YADE's stress with our sign, the
    cell's deformation since it was attached, YADE's unbalanced force), calls its update() for the six
    strain rates, and sets O.cell.velGrad. YADE's save files do not keep the controller: `detach`
    before O.save, attach again after O.load.

    Args:
        controller: an engines.TrueTriaxialServo or engines.StressProbe, started (set_goal or begin).
        stiffness: the six diagonal cell stiffnesses that scale its gain (engines.cell_stiffness of
            the scene).
        O: YADE's Omega (None: ``yade.O``).
        label: the PyRunner's label; another controller needs another label.

    Returns:
        CellAdapter: the adapter (its ``calls`` count the steps it ran).

    Raises:
        ValueError: a YADE scene without a NewtonIntegrator.

    Example:
        Inside yade-double, state 2 of Table C1 reached by our servo on YADE's dynamics:

        >>> import numpy as np
        >>> from yade import O
        >>> from trueaniso import engines, specimen_file, yade_adapter, yade_bridge
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> _ = yade_bridge.yade_scene_from(scene, O, damping=0.4)
        >>> servo = engines.TrueTriaxialServo()
        >>> servo.set_goal(0.0, 110e3, 100e3)
        >>> adapter = yade_adapter.attach(servo, engines.cell_stiffness(scene))
        >>> yade_adapter.run_until_done(servo, O)
        True
        >>> print(servo.status, "%.0f %.0f %.0f kPa" % tuple(np.array(servo.stress[:3]) / 1e3))
        reached 95 95 110 kPa
        >>> yade_adapter.detach(O)
    """
    from yade import PyRunner
    if O is None:
        from yade import O
    import __main__
    adapter = CellAdapter(controller, stiffness, O)
    name = "_trueaniso_adapter_" + label
    setattr(__main__, name, adapter)  # PyRunner commands run in __main__'s namespace
    _ACTIVE[label] = adapter
    engines = [e for e in O.engines if getattr(e, "label", "") != label]
    newton = [k for k, e in enumerate(engines) if type(e).__name__ == "NewtonIntegrator"]
    if not newton:
        raise ValueError("the YADE scene needs a NewtonIntegrator")
    # A controller is no part of a YADE scene file: a scene saved (O.save) with it attached and
    # loaded in another process runs a command whose name is gone, which would say only "NameError:
    # name '_trueaniso_adapter_...' is not defined". The command says why.
    named = "" if label == DEFAULT_LABEL else ", label=%r" % label  # the way out names the controller's own label
    missing = ("the PyRunner %r calls a trueaniso controller, which a YADE scene file does not keep: this scene "
               "was saved (O.save) with it attached and loaded without it. Attach a new one after O.load "
               "(yade_adapter.attach(controller, stiffness%s) replaces it), or yade_adapter.detach(O%s) before "
               "O.save" % (label, named, named))
    command = "if %r not in globals(): raise RuntimeError(%r)\n%s()" % (name, missing, name)
    engines.insert(newton[0], PyRunner(command=command, iterPeriod=1, label=label))
    O.engines = engines
    return adapter


def detach(O=None, label=DEFAULT_LABEL):
    """Remove the controller attached with `label` from YADE's engines.

    Example:
        Inside yade-double:

        >>> from yade import O
        >>> from trueaniso import engines, specimen_file, yade_adapter, yade_bridge
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> _ = yade_bridge.yade_scene_from(scene, O)
        >>> servo = engines.TrueTriaxialServo()
        >>> servo.set_goal(0.0, 110e3, 100e3)
        >>> _ = yade_adapter.attach(servo, engines.cell_stiffness(scene))
        >>> yade_adapter.detach(O)
        >>> yade_adapter.DEFAULT_LABEL in [e.label for e in O.engines]
        False
    """
    if O is None:
        from yade import O
    O.engines = [e for e in O.engines if getattr(e, "label", "") != label]
    _ACTIVE.pop(label, None)


def set_friction(O, mu):
    """Friction coefficient `mu` on YADE's materials and on every existing contact (YADE keeps it per contact).

    A probe suppresses sliding with mu = 1e23, as our StressProbe does.

    Example:
        Inside yade-double:

        >>> from yade import O
        >>> from trueaniso import specimen_file, yade_adapter, yade_bridge
        >>> _ = yade_bridge.yade_scene_from(specimen_file.load("tests/data/spheres-150-s4.npz")[0], O)
        >>> yade_adapter.set_friction(O, 1e23)
        >>> min(I.phys.tangensOfFrictionAngle for I in O.interactions if I.isReal)
        1e+23
    """
    angle = math.atan(mu)
    for m in O.materials:
        m.frictionAngle = angle
    for I in O.interactions:
        if I.isReal:
            I.phys.tangensOfFrictionAngle = mu


def run_until_done(controller, O, chunk=1000, max_steps=5_000_000):
    """Run YADE in chunks of `chunk` steps until the attached controller is done or `max_steps` ran.

    Returns:
        bool: whether the controller is done.

    Example:
        Inside yade-double, a probe of $E_z$ through the adapter (sliding suppressed):

        >>> import numpy as np
        >>> from yade import O, utils
        >>> from trueaniso import engines, specimen_file, yade_adapter, yade_bridge
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> _ = yade_bridge.yade_scene_from(scene, O)
        >>> yade_adapter.set_friction(O, 1e23)
        >>> probe = engines.StressProbe()
        >>> probe.axis, probe.max_strain_rate = 2, 10.0
        >>> probe.begin(-np.diag(np.array(utils.getStress())))
        >>> _ = yade_adapter.attach(probe, engines.cell_stiffness(scene))
        >>> yade_adapter.run_until_done(probe, O)
        True
        >>> print("E_z = %.0f MPa" % (probe.young_modulus / 1e6))
        E_z = 278 MPa
    """
    steps = 0
    while not controller.done and steps < max_steps:
        O.run(chunk, True)
        steps += chunk
    return controller.done
