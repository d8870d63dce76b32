"""Our servo and probe inside a YADE simulation (yade-double), with YADE's own dynamics and its
Hertz-Mindlin law: a thin adapter called every step by a PyRunner.

    from trueaniso import yade_adapter
    servo = engines.TrueTriaxialServo(); servo.set_goal(0.5, 120e3)
    yade_adapter.attach(servo, stiffness)        # a PyRunner before NewtonIntegrator
    O.run(...) until yade_adapter.finished()

The adapter measures what our controllers read (YADE's getStress with our sign, the cell's
log strain, YADE's unbalanced force), calls the controller's C++ update(), and sets
O.cell.velGrad (YADE applies a new velGrad from the next step on). The stiffness estimate that
scales the gain is our affine estimate of the imported scene (trueaniso.engines.cell_stiffness),
constant over the small strains of a state or a probe.
"""
import math

import numpy as np

_ACTIVE = {}


class CellAdapter:
    def __init__(self, controller, stiffness, O):
        self.controller = controller
        self.stiffness = np.asarray(stiffness, dtype=float)
        self.O = O
        self.ref = np.array([O.cell.hSize[k][k] for k in range(3)])
        self.calls = 0

    def measure(self):
        from yade import utils
        O = self.O
        stress = -np.diag(np.array(utils.getStress()))
        h = np.array([O.cell.hSize[k][k] for k in range(3)])
        strain = -np.log(h / self.ref)
        unbalanced = utils.unbalancedForce()
        if not math.isfinite(unbalanced):
            unbalanced = 1.0
        return stress, strain, unbalanced

    def __call__(self):
        from yade import Matrix3
        stress, strain, unbalanced = self.measure()
        rates = self.controller.update(stress, strain, self.stiffness, unbalanced, self.O.dt)
        self.O.cell.velGrad = Matrix3(rates[0], 0, 0, 0, rates[1], 0, 0, 0, rates[2])
        self.calls += 1
        if self.controller.done:
            self.O.pause()


def attach(controller, stiffness, O=None, label="trueanisoController"):
    """Insert a PyRunner calling `controller` every step, just before YADE's NewtonIntegrator."""
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
    engines.insert(newton[0], PyRunner(command="%s()" % name, iterPeriod=1, label=label))
    O.engines = engines
    return adapter


def detach(O=None, label="trueanisoController"):
    if O is None:
        from yade import O
    O.engines = [e for e in O.engines if getattr(e, "label", "") != label]
    _ACTIVE.pop(label, None)


def set_friction(O, mu):
    """Friction of the material and of every existing contact (YADE keeps it per interaction)."""
    angle = math.atan(mu)
    for m in O.materials:
        m.frictionAngle = angle
    for I in O.interactions:
        if I.isReal:
            I.phys.tangensOfFrictionAngle = mu


def run_until_done(controller, O, chunk=1000, max_steps=5_000_000):
    steps = 0
    while not controller.done and steps < max_steps:
        O.run(chunk, True)
        steps += chunk
    return controller.done
