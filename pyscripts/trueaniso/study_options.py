"""The options run_states.py and run_study.py share: one definition each, one check, and the option
objects (options.ServoOptions, ProbeOptions, PathOptions) they make for study.run_states.

Both scripts run a study: the same specimen, servo, probe and run options mean the same in each
(run_study.py adds the specimen's preparation, the static solves and the report; run_states.py the
other loading paths and MPI workers). --help says what an option does and its default; why a
default is what it is, with the measurements, is in the manual pages each help names.
"""
from . import cli, options, progress, resources
from .refusal import InputError


def add_probe_options(p, probes_default):
    """--gamma, --probes, --rotations, --skip-detection, --probe-sides, --damping."""
    from . import triaxial
    lo, hi = triaxial.GAMMA_RANGE
    p.add_argument("--gamma", type=cli.finite, default=options.ProbeOptions.gamma,
                   help="probe size gamma of Eq. 12, in [%g, %g] (docs/triaxial.md)" % (lo, hi))
    p.add_argument("--probes", help="probe axes, each at most once: letters of x, y, z (e.g. zxy), or names separated "
                                    "by commas, where the shear probes yz, xz, xy (G_ij) may be given too (e.g. "
                                    "z,x,y,yz,xz,xy; one shear probe alone: xy, with its comma). Default: %s"
                                    % probes_default)
    p.add_argument("--rotations", choices=("free", "restrained"), default="free",
                   help="particle rotations during probes")
    p.add_argument("--skip-detection", action="store_true",
                   help="no contact detection during probes (nothing slides, the network cannot change)")
    p.add_argument("--probe-sides", choices=options.PROBE_SIDES, default=options.ProbeOptions.sides,
                   help="two: each probe also run against its sign from the same relaxed state, the half difference "
                        "kept (what the held state does alone cancels); one: the paper's one-sided probe; auto: two "
                        "on clumps with rotations free, one elsewhere (docs/triaxial.md, 'Two-sided probes')")
    p.add_argument("--damping", type=cli.finite, default=options.ServoOptions.damping,
                   help="local non-viscous damping while states are reached and probed, in (0, 1)")


def add_servo_options(p):
    """--mu, --path-rate, --time-step, --rolling-stiffness, --rolling-friction."""
    p.add_argument("--mu", type=cli.finite, default=options.ServoOptions.friction,
                   help="friction coefficient while states are reached (the paper's; probes always suppress sliding)")
    cli.add_path_rate_option(p)
    cli.add_time_step_option(p, study=True)
    p.add_argument("--rolling-stiffness", type=cli.non_negative, default=0.0,
                   help="rolling resistance (not in the paper; docs/rolling.md): beta of the rolling stiffness "
                        "k_r = beta k_s rbar^2, from the specimen on through states and probes; 0 = off. Give "
                        "--rolling-friction with it")
    p.add_argument("--rolling-friction", type=cli.non_negative, default=0.0,
                   help="rolling resistance: eta_r of the largest rolling moment eta_r rbar N; 0 = off")


def add_run_options(p, out_default=None, mpi=False):
    """--threads, --out, --wait, --force-new, --progress-every."""
    cli.add_threads_option(p, study=True, mpi=mpi)
    p.add_argument("--out", required=out_default is None, default=out_default,
                   help="results directory (one study; created if missing)")
    p.add_argument("--wait", action="store_true", help="if another run is writing --out, wait for it instead of "
                                                       "refusing")
    p.add_argument("--force-new", action="store_true",
                   help="start a new study in --out: the old one is moved into --out/superseded/, not deleted")
    p.add_argument("--progress-every", type=cli.non_negative, default=progress.EVERY,
                   help="seconds between progress lines of long work (0: after every chunk of steps)")


def probe_axes(text, path):
    """The probe axes as names: letters (zxy) or comma-separated names (z,x,y,yz,xz,xy)."""
    axes = options.AXES
    if text is None:
        return list(axes) if path == "cross-anisotropic" else ["z", "x", "y"]
    shear = [n for n in axes if len(n) == 2]
    if text.strip() in shear:
        # Read as letters, 'xy' would run the normal probes x and y, not the shear probe the help
        # and the CSV call xy: two readings, so neither is guessed.
        n = text.strip()
        raise InputError("--probes %r is ambiguous: the shear probe %s, or the normal probes %s and %s? Write "
                         "'%s,' for the shear probe alone, '%s,%s' for the two normal probes"
                         % (text, n, n[0], n[1], n, n[0], n[1]))
    if "," in text:
        names = [s.strip() for s in text.split(",")]
        if len(names) == 2 and names[0] and not names[1]:  # 'xy,': a list of one name, as a 1-tuple is written
            names = names[:1]
    else:
        names = list(text)
    unknown = [n for n in names if n not in axes]
    if not names or unknown:
        # 'yx,' is not a repeat of anything: it is no name, so it is named as such.
        named = [repr(n) for n in unknown if n]
        what = ("%s %s no probe's name" % (", ".join(named), "is" if len(named) == 1 else "are") if named
                else "an empty item" if names else "no probe given")
        raise InputError("--probes %r: %s. Give letters of x, y, z (e.g. zxy), or names separated by commas "
                         "among x, y, z, yz, xz, xy" % (text, what))
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise InputError("--probes %r names %s more than once; each probe runs once a state"
                         % (text, " and ".join(repeated)))
    return names


def check(o):
    """The checks of the shared options that need no specimen (before any work)."""
    from . import triaxial
    lo, hi = triaxial.GAMMA_RANGE
    if not lo <= o.gamma <= hi:
        raise InputError("--gamma %g is outside [%g, %g]: above, the probe is no longer elastic; below, its "
                         "increment nears the stress noise of a held state (docs/triaxial.md)" % (o.gamma, lo, hi))
    if not 0 <= o.damping < 1:
        raise InputError("--damping must lie in [0, 1)")
    if o.damping == 0:
        # The contact law dissipates nothing itself (no viscous damping): without local damping the
        # kinetic energy stays, and a state never meets the servo's unbalanced-force criterion.
        raise InputError("--damping 0: the contact law has no viscous damping, so without local damping nothing "
                         "dissipates the packing's kinetic energy and no state settles below the servo's "
                         "unbalanced-force tolerance; give a damping in (0, 1) (default %g)" % options.ServoOptions.damping)
    if not o.mu > 0:
        raise InputError("--mu must be > 0 (the loading friction; probes suppress sliding themselves)")
    resources.check_threads(o.threads)


def objects(o, path="true-triaxial"):
    """(PathOptions, ServoOptions, ProbeOptions) of the parsed options, checked."""
    return (options.PathOptions(path=path, probes=tuple(o.probe_axes)),
            options.ServoOptions(damping=o.damping, friction=o.mu, path_rate=o.path_rate, time_step=o.time_step,
                                 rolling_stiffness=o.rolling_stiffness, rolling_friction=o.rolling_friction),
            options.ProbeOptions(gamma=o.gamma, damping=o.damping, restrain_rotations=o.rotations == "restrained",
                                 skip_detection=o.skip_detection, sides=o.probe_sides,
                                 time_step=getattr(o, "probe_time_step", None) or o.time_step))
