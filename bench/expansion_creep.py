"""Where a preparation's free expansion waits: its signed stress error, stepped on from its checkpoint.

    /usr/bin/python3 bench/expansion_creep.py --checkpoint specimens/.clump2-69532-s1.npz.checkpoint \
        --steps 3200 --every 100

The radius expansion ends when the mean stress is within the stress tolerance of the target (and the
unbalanced force low); the preparation's log says only the error's size. This steps the checkpoint's
scene on, in memory (the checkpoint is only read), with the expansion's servo as the preparation
builds it: its recipe's target (a sphere recipe grown to its switch pressure stops there), gain,
deviator hold, damping and inertial number (prepare_spheres' and prepare_clumps' defaults, a named
variant's own values over them), the checkpoint's d50 and time-step cap, one engine thread. It stops
at the first sample at which the servo's end criterion holds (the preparation checks it at the end
of each 2,000 steps).

Reading it: an error of one sign that holds level (its trend small against it) while the radii keep
growing is a packing that relaxes as fast as the servo grows it, creep; one that falls steadily is
an approach that ends by itself; one that changes sign is noise. One JSON line per sample (step,
error = target - p in Pa, the radius scale grown since the start, unbalanced force, whether the end
criterion holds), then the summary: the error's mean, least and largest, its trend (Pa per 1000
steps, a straight line through the samples), the radii's growth a step, and the step at which the
criterion held, if it did (docs/studies/paper-size.md, "Where the clump preparations wait").
"""
import inspect
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402,F401  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--checkpoint", required=True, help="a preparation checkpoint (.NAME.npz.checkpoint), in its expansion")
    p.add_argument("--steps", type=cli.at_least(1), default=3200, help="steps to run")
    p.add_argument("--every", type=cli.at_least(1), default=None,
                   help="steps between samples (default: 100, or --steps when fewer)")
    o = cli.parse(p)
    if os.path.isdir(o.checkpoint):
        cli.fail("--checkpoint %s is a directory, not a preparation checkpoint" % o.checkpoint)
    if not os.path.isfile(o.checkpoint):
        cli.fail("--checkpoint %s: no such file" % o.checkpoint)
    if o.every is None:
        o.every = min(100, o.steps)
    if o.every > o.steps:
        cli.fail("--every (%d) is more than --steps (%d): no sample would be taken" % (o.every, o.steps))
    return o


def servo_settings(recipe):
    """gain, damping, inertial number and tolerances of the expansion the checkpoint's `recipe` (its
    settings, prepare_specimen.settings) runs: the preparation function's defaults, a named variant's
    own values over them, the recorded inertial number."""
    from trueaniso import clump_recipes, clump_specimen, specimen
    assembly = recipe.get("assembly", "sphere")
    fn = specimen.prepare_spheres if assembly == "sphere" else clump_specimen.prepare_clumps
    d = {k: v.default for k, v in inspect.signature(fn).parameters.items()}
    d = {k: d[k] for k in ("gain", "damping", "inertial_number", "stress_tolerance", "prep_unbalanced")}
    named = clump_recipes.variant(assembly, recipe["recipe"]) if recipe.get("recipe") else {}
    d.update({k: v for k, v in named.items() if k in d})
    if "inertial_number" in recipe:
        d["inertial_number"] = recipe["inertial_number"]
    # The sphere recipe grown to its switch pressure (unload=False) stops its expansion there.
    pressure = float(recipe["pressure"])
    d["target"] = pressure if named.get("unload", True) else float(recipe.get("switch_pressure", pressure))
    d["hold_deviator"] = named.get("hold_deviator")  # clump1's variant: the deviator held at this gain
    return d


def main():
    o = options()
    import numpy as np
    from trueaniso import dem, engines, specimen, specimen_file
    scene, meta = specimen_file.load(o.checkpoint)
    ck = (meta.get("parameters") or {}).get("checkpoint")
    if not ck:
        cli.fail("%s is a specimen, not a preparation checkpoint" % o.checkpoint)
    place, recipe = ck["place"], ck["recipe"]
    if place["stage"] != "expansion":
        cli.fail("%s was written in the preparation's stage %r, not in its expansion (the stage whose end this "
                 "looks at): a checkpoint of a later run of the preparation may be" % (o.checkpoint, place["stage"]))
    lacks = [k for k in ("pressure", "d50") if k not in recipe]
    if lacks:
        cli.fail("%s records no %s: not a checkpoint of prepare_specimen.py" % (o.checkpoint, " or ".join(lacks)))
    engines.set_threads(1)
    dem.time_step_rule = recipe.get("time_step", cli.UNRECORDED_TIME_STEP)  # as the preparation ran
    d = servo_settings(recipe)
    # The rate cap is the target pressure's, as the preparation's (specimen.py, clump_specimen.py).
    rate = dem.strain_rate_for_inertial_number(d["inertial_number"], recipe["d50"], scene.density,
                                               float(recipe["pressure"]))
    grow = specimen.expansion(d["target"], d["gain"], rate, d["stress_tolerance"], d["prep_unbalanced"])
    if d["hold_deviator"] is not None:
        grow.hold_deviator = True
        grow.deviator_gain = d["hold_deviator"]
    chain = dem.Chain(scene, damping=d["damping"], controllers=[grow], max_dt=place["max_dt"])
    steps, errors, t0, done, met = [], [], time.time(), 0, None
    while done < o.steps and met is None:
        done += chain.run(min(o.every, o.steps - done))
        err = d["target"] - float(grow.pressure)
        steps.append(done)
        errors.append(err)
        if grow.reached:
            met = done
        print(json.dumps(dict(step=done, error=round(err, 2), scale=float(grow.scale), unbalanced=float(grow.unbalanced),
                              criterion=bool(grow.reached))), flush=True)
    e = np.array(errors)
    trend = float(np.polyfit(steps, e, 1)[0]) * 1000.0 if len(e) > 1 else None
    print(json.dumps(dict(checkpoint=os.path.basename(o.checkpoint), expansion_steps_before=place["steps"]["expansion"],
                          steps=done, error_mean=round(float(e.mean()), 2), error_min=round(float(e.min()), 2),
                          error_max=round(float(e.max()), 2), one_sign=bool((e > 0).all() or (e < 0).all()),
                          trend_per_1000_steps=None if trend is None else round(trend, 2),
                          growth_per_step=(float(grow.scale) - 1.0) / done, criterion_met_at=met,
                          seconds=round(time.time() - t0, 1), **d)), flush=True)


if __name__ == "__main__":
    cli.guarded(main)
