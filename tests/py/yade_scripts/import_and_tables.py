"""Inside a yade-double session: `import run_states` must only import, and
trueaniso.param_table must read a table exactly as YADE's own readers do.
Arguments: pyscripts directory, table path, output JSON."""
import json
import sys

pyscripts, table, out = sys.argv[1], sys.argv[2], sys.argv[3]
sys.path.insert(0, pyscripts)
import run_states  # noqa: E402 - must not run main(), which would end the session

from trueaniso import param_table  # noqa: E402
from yade import utils  # noqa: E402

head, values = param_table.columns_and_values(table)
names = param_table.parameter_columns(head)
theirs_raw = utils.TableParamReader(table).paramDict()
defaults = dict(n=1000, seed=1, pressure=100e3, quiet=False, out=None)
lines = {}
for line in sorted(values):
    raw_ours = {names.get(h, h): v for h, v in zip(head, values[line])}
    raw_theirs = {k: v for k, v in theirs_raw[line].items() if k != "description"}
    lines[line] = dict(raw_equal=raw_ours == raw_theirs, raw_ours=raw_ours, raw_theirs=raw_theirs,
                       ours=param_table.read_line(table, line),
                       yade=param_table.read_line_in_yade(table, line, defaults))
json.dump(dict(imported=hasattr(run_states, "main"), lines={str(k): v for k, v in lines.items()}), open(out, "w"),
          default=repr)
