"""The time step rules of the engines' TimeStepper, by name (docs/time-step.md): the one home of the
names, their factors and which is the default, read by the engine chains (dem.py) and the scripts'
--time-step (cli.py) alike; no engine is loaded by importing it.

name -> (per_axis, safety). "per-axis" is the per-axis bound at the largest factor at which undamped
packings of spheres, clump1 and clump2 keep their energy over 100,000 steps (the runs' local damping
is the margin), the default of the states and probes; "smallest-inertia" is the preparation's, and
the rule of every state and probe made before per-axis was their default, kept as a named option.
"""
RULES = {"smallest-inertia": (False, 0.5), "per-axis": (True, 0.8)}
# The default of the states and the probes: 1.6 (spheres) to 3 (clumps) times fewer steps, the
# physics unchanged against the scatter between seeds (docs/time-step.md).
DEFAULT = "per-axis"
# The default of the preparation: per-axis moves the void ratio of the 1000-sphere recipe by 25 times
# the scatter between seeds (docs/time-step.md, "The preparation"), so it stays a named option there.
PREPARATION = "smallest-inertia"
# The rule of a specimen file or a study that records none (made before the rule was recorded).
LEGACY = "smallest-inertia"
# The rule whose step is the unit of time of the servos' and the probe's per-step settings (path rate,
# gain, step counts; scene.reference_dt): under any other rule they load at the same rate in time.
REFERENCE = "smallest-inertia"
