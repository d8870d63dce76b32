"""True-triaxial states and their x, y, z stress probes on a specimen, one CSV row per state and probe.

    yade-double -n -x pyscripts/run_states.py --specimen S.npz --path cross-anisotropic --out results/fig16
    yade-double -n -x pyscripts/run_states.py --specimen S.npz --table-c1 --out results/table-c1
    yade-double -n -x pyscripts/run_states.py --specimen S.npz --states 0.5:140e3,0:60e3 --out results/x
    /usr/bin/python3 pyscripts/run_states.py --specimen S.npz --ids 1,5,21 --out results/y
    yade-batch states.table pyscripts/run_states.py      (one run per table line; docs/runs.md)
    mpiexec -n 3 /usr/bin/python3 -m mpi4py.futures pyscripts/run_states.py --mpi --table-c1 ...
                                                         (loading paths on 2 MPI workers; docs/runs.md)

--path cross-anisotropic follows the paper's Fig. 16 instead: sigma_h = sigma_x = sigma_y held at
100 kPa while sigma_v = sigma_z takes the values of --sigma-v, probed on x, y, z and on the shear
strains yz, xz, xy (G_vh, G_hh; docs/cell.md).
Writes probes.csv (one row per state and probe direction), metadata.json (the study's fingerprint)
and a checkpoint per state. The output directory is one study: a rerun continues it (adding
states is fine), or refuses in one line if it asks for something else (docs/runs.md).
"""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__)))
from trueaniso import start_guard  # noqa: E402  (first: Ctrl-C while numpy and the engines load is one line)
# An MPI worker (a rank other than 0: mpi4py.futures' master is rank 0) ends silently, as it does
# once loaded (cli.release_start_guard): a Ctrl-C on mpiexec within its first second would print
# the line once a worker beside the master's.
start_guard.install(quiet=next((os.environ[v] for v in ("OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK")
                                if v in os.environ), "0") != "0")
try:
    from trueaniso import cli, progress, resources, specimen_file, study, study_dir, study_options, triaxial
except ImportError as exc:  # the compiled module not built (or a Debian package missing): one line, not a traceback
    sys.stderr.write("error: %s\n" % exc)
    os._exit(2)


def parser():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file from prepare_specimen.py (.npz)")
    p.add_argument("--assembly", type=cli.assembly,
                   help="refuse a specimen of another assembly (the specimen file says which it is)")
    p.add_argument("--states", help="b:sigma_z pairs, sigma_z in Pa, comma separated (e.g. 0.5:140e3,0:60e3); "
                                    "a state's id is its Table C1 number, else b<b>_sz<sigma_z>")
    p.add_argument("--table-c1", action="store_true", help="all 39 states of the paper's Table C1")
    p.add_argument("--ids", help="a subset of Table C1 states by number, e.g. 1,5,21")
    p.add_argument("--path", choices=triaxial.PATHS, default="true-triaxial",
                   help="loading path: true-triaxial (constant b and p = 100 kPa, Table C1; give --states, --table-c1 "
                        "or --ids) or cross-anisotropic (Fig. 16: sigma_x = sigma_y = 100 kPa, sigma_z = --sigma-v)")
    p.add_argument("--sigma-v", help="cross-anisotropic path: the vertical stresses sigma_z in Pa, comma separated "
                                     "(default %s); a state's id is sv<sigma_v in kPa>"
                                     % ",".join("%g" % v for v in triaxial.CROSS_ANISOTROPIC_SIGMA_V))
    study_options.add_probe_options(p, "zxy on the true-triaxial path, all six on the cross-anisotropic one")
    study_options.add_servo_options(p)
    study_options.add_run_options(p, mpi=True)
    p.add_argument("--host", choices=study.HOSTS, default="trueaniso",
                   help="who steps the states and probes: trueaniso (our stepper) or yade (YADE's own loop with the "
                        "plugin's TrueTriaxialServo, StressProbe and FabricRecorder in O.engines; run under yade-double "
                        "with YADE_PREFIX=<repository>/build/yade-prefix, docs/yade-peer.md). The same specimen, "
                        "states, probes and CSV; a study is stepped by one host")
    p.add_argument("--mpi", action="store_true",
                   help="run the states on MPI workers, one state a task, each loading path in order: start as "
                        "mpiexec -n K /usr/bin/python3 -m mpi4py.futures pyscripts/run_states.py --mpi ... (K-1 "
                        "workers; --threads defaults to 1)")
    return p


def mpi_ranks():
    """(ranks, this rank) of the mpiexec that started this process (Open MPI's or MPICH's
    environment), or (1, 0) outside one."""
    for size, rank in (("OMPI_COMM_WORLD_SIZE", "OMPI_COMM_WORLD_RANK"), ("PMI_SIZE", "PMI_RANK")):
        if size in os.environ:
            try:
                return int(os.environ[size]), int(os.environ.get(rank, 0))
            except ValueError:
                pass
    return 1, 0


def validate(o):
    """Every check that needs no work; returns the states."""
    ranks, rank = mpi_ranks()
    if ranks > 1 and not o.mpi:
        # Each rank would run its own study in --out: one holds the lock, the others refuse, and
        # mpiexec then kills the one at work. Rank 0 says so and fails; the others leave with status
        # 0, since a rank failing first would have mpiexec stop rank 0 before it has said why.
        if rank != 0:
            raise SystemExit(0)
        raise cli.InputError("mpiexec started this script on %d ranks without --mpi; for MPI workers start as "
                             "mpiexec -n K /usr/bin/python3 -m mpi4py.futures pyscripts/run_states.py --mpi ..."
                             % ranks)
    problem = cli.output_problem(o.out)  # first: the thread count below is read from what --out holds
    if problem:
        raise cli.InputError(problem)
    cli.resolve_threads(o)
    cli.resolve_path_rate(o)
    cli.resolve_study_time_step(o)
    if o.path == "cross-anisotropic":
        if o.states is not None or o.table_c1 or o.ids is not None:
            raise cli.InputError("--path cross-anisotropic takes its states from --sigma-v, not from --states, "
                                 "--table-c1 or --ids")
    elif o.sigma_v is not None:
        raise cli.InputError("--sigma-v belongs to --path cross-anisotropic")
    elif sum(bool(x) for x in (o.states is not None, o.table_c1, o.ids is not None)) != 1:
        raise cli.InputError("give exactly one of --states, --table-c1, --ids")
    try:
        if o.path == "cross-anisotropic":
            states = triaxial.cross_anisotropic_states(parse_sigma_v(o.sigma_v) if o.sigma_v is not None
                                                       else triaxial.CROSS_ANISOTROPIC_SIGMA_V)
        elif o.states is not None:
            states = study.parse_states(o.states)
        elif o.ids is not None:
            try:
                states = study.table_states(study.parse_ids(o.ids))
            except ValueError as exc:
                raise ValueError("--ids: %s" % exc) from None
        else:
            states = study.table_states()
        for _, b, sz in states:
            triaxial.validate_path_state(o.path, b, sz)
    except ValueError as exc:
        raise cli.InputError(str(exc)) from None
    o.probe_axes = study_options.probe_axes(o.probes, o.path)
    study_options.check(o)
    if o.host != "trueaniso":
        if o.mpi:
            raise cli.InputError("--host %s steps the states in this process's YADE: it takes no --mpi workers" % o.host)
        study.host_named(o.host)  # not under yade-double, or without the plugin: said before any work
    try:
        arrays, meta = specimen_file.read(o.specimen)
    except specimen_file.SpecimenFileError as exc:
        raise cli.InputError(str(exc)) from None
    try:
        assembly = study.assembly_of(meta, arrays["member_begin"])
    except cli.InputError as exc:
        raise cli.InputError("%s: %s" % (o.specimen, exc)) from None
    problem = triaxial.rolling_problem(o.rolling_stiffness, o.rolling_friction, assembly != "sphere")
    if problem:
        raise cli.InputError(problem)
    if o.assembly and assembly != o.assembly:
        what = ("holds clumps but records no assembly (saved outside prepare_specimen.py), so --assembly cannot be "
                "checked; leave it out" if assembly == study.UNNAMED_CLUMPS else "is a %s specimen, not %s (--assembly)"
                % (assembly, o.assembly))
        raise cli.InputError("%s %s" % (o.specimen, what))
    return states


def parse_sigma_v(text):
    """'60e3,80e3' -> [60e3, 80e3] (Pa); refuses an empty list or item and what is not a number."""
    items = [s.strip() for s in text.split(",")]
    if not any(items):
        raise ValueError("--sigma-v names no stress (give Pa values, e.g. 60e3,150e3)")
    if not all(items):  # "100e3," or "60e3,,140e3": a stress left out, perhaps the one meant (as --ids)
        raise ValueError("--sigma-v %r has an empty item: give Pa values separated by commas, e.g. 60e3,150e3" % text)
    try:
        return [float(s) for s in items]
    except ValueError:
        raise ValueError("--sigma-v %r: expected stresses in Pa separated by commas, e.g. 60e3,150e3" % text) from None


def mpi_executor(o):
    """The MPI pool of `python3 -m mpi4py.futures` (None without --mpi), checked before any work."""
    if not o.mpi:
        return None
    try:
        from mpi4py import MPI
        from mpi4py.futures import MPIPoolExecutor, _lib
    except ImportError:
        raise cli.InputError("--mpi needs mpi4py (Debian: python3-mpi4py openmpi-bin)") from None
    start = ("start as mpiexec -n K /usr/bin/python3 -m mpi4py.futures pyscripts/run_states.py --mpi ... with K >= 2 "
             "(K-1 workers)")
    if MPI.COMM_WORLD.Get_size() < 2:
        raise cli.InputError("--mpi: no MPI workers; " + start)
    if getattr(_lib, "SharedPool", None) is None:
        # mpiexec ran the script itself on every rank: each would be a master with its own pool
        # and write the study (the pool of `-m mpi4py.futures` is the one this script expects).
        # Rank 0 says so; the others leave quietly, so the line is printed once.
        if MPI.COMM_WORLD.Get_rank() != 0:
            raise SystemExit(2)
        raise cli.InputError("--mpi: mpiexec started this script on all %d ranks, without mpi4py.futures; "
                             % MPI.COMM_WORLD.Get_size() + start)
    if not o.threads:
        o.threads = 1  # workers x threads within the cores; a thread count is part of the study
    workers = MPI.COMM_WORLD.Get_size() - 1
    if workers * o.threads > resources.cores():
        # Not refused (a cluster node may count cores otherwise), but said: OpenMP teams on shared
        # cores wait at every barrier for a time slice (docs/benchmarks.md, "Stepper changes").
        if o.threads == 1:  # one-thread workers only take turns: no barrier waits, nothing to gain either
            print("warning: %d workers take turns on this machine's %d cores; %d workers (mpiexec -n %d) would "
                  "finish about as soon, with less memory" % (workers, resources.cores(), resources.cores(),
                                                              resources.cores() + 1), flush=True)
        else:
            print("warning: %d workers x %d engine threads exceed this machine's %d cores; each team waits for the "
                  "others at every barrier (a study continued at its own thread count keeps it: start a new one "
                  "with --threads 1 to use one thread a worker)" % (workers, o.threads, resources.cores()), flush=True)
    return MPIPoolExecutor()


def main(argv=None):
    t0 = time.time()
    o = cli.parse(parser(), argv)
    states = validate(o)
    cli.saves_work_in(lambda: study_dir.has_saved_work(o.out),
                      complete=lambda: study_dir.has_rows(o.out, [i for i, _, _ in states], o.probe_axes),
                      resumes=cli.RESUMES_STUDY)
    executor = mpi_executor(o)
    if o.threads:
        from trueaniso import resources
        resources.use_threads(o.threads)
    try:
        path, servo, probe = study_options.objects(o, o.path)
        study.run_states(o.specimen, states, o.out, path=path, servo=servo, probe=probe, wait=o.wait, host=o.host,
                         force_new=o.force_new, progress_every=o.progress_every, log=progress.say, executor=executor)
    except triaxial.StateNotReached as exc:
        cli.fail(str(exc), 1)
    finally:
        if executor is not None:
            executor.shutdown(wait=False, cancel_futures=True)
    # The whole run, as run_study.py's last line: each state's "done" line counts its probes only,
    # and its "reached" line the loading.
    progress.say("results: %s; this run took %.1f s in all"
                 % (os.path.join(o.out, "probes.csv"), time.time() - t0))


if __name__ == "__main__":  # also under yade-double -x; an import (even inside YADE) runs nothing
    cli.guarded(main, resumable=True)
else:  # loaded, not run (mpi4py.futures' workers load the script): no start-up guard left behind
    cli.release_start_guard()
