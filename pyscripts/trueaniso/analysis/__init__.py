"""Analysis of study results: the orthotropic hyperelastic model (paper section 4.1) and figures.
Pure numpy/scipy/matplotlib on the CSV written by pyscripts/run_states.py; reading the tables and
the figures need no compiled module, the analysis chain (report, path_fidelity, zeta_contrast)
uses the engines' fabric and micromechanics."""
import os
import sys


def _one_line_when_unbuilt(kind, value, tb, _default=sys.excepthook):
    """A tool of this folder run on a machine without the build ends with the one line that says
    what to do, as the scripts give it, not a traceback that ends with it."""
    if issubclass(kind, ImportError) and "compiled module _trueaniso" in str(value):
        sys.stderr.write("error: %s\n" % value)
        sys.stderr.flush()
        os._exit(2)
    _default(kind, value, tb)


if sys.argv and sys.argv[0] == "-m" or (sys.argv and os.path.basename(os.path.dirname(os.path.abspath(sys.argv[0])))
                                         == "analysis"):
    sys.excepthook = _one_line_when_unbuilt  # run as a tool (python3 -m trueaniso.analysis.X, or its file)
