"""One schema per file trueaniso reads, and one way to refuse a file that does not fit.

The schemas are JSON Schema (draft 7) files in ``schemas/``, checked with Debian's
python3-jsonschema: ``specimen`` (the metadata of a specimen file), ``checkpoint`` (a study's
state checkpoint: a specimen whose parameters name its state and study), ``prep_checkpoint`` (a
preparation's checkpoint: a specimen whose parameters hold its recipe and place), ``study`` (a study's
metadata.json), ``probes`` (a row of probes.csv, its cells as text), ``statics_record`` (a
study's statics_*.json) and ``param_table`` (a line of a yade-batch table), ``fig16_states`` and ``clump_anisotropy`` (the
JSON the report's --fig16 and --clumps read). The arrays of a
specimen file are a declarative table beside them (``specimen_arrays.json``: kind, shape in the
file's own counts, finiteness). Every property has a description: the formats' reference pages
are made from these files.

A number in a schema is a finite number (JSON has no NaN, but Python's json reads one), never a
boolean. A file that does not fit is refused in one line, ``<file>: <field>: <what>``, the field
as a dotted path into the file (``material.density``, ``states.5.sigma_z``); scripts print it as
``error: ...`` with exit status 2 (cli.guarded).
"""
import functools
import json
import math
import os

import jsonschema

from .refusal import InputError

__all__ = ["check", "load_json", "problem", "FileInvalid"]

SCHEMAS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "schemas")
NAMES = ("specimen", "checkpoint", "prep_checkpoint", "study", "probes", "statics_record", "param_table", "fig16_states",
         "clump_anisotropy")


class FileInvalid(InputError):
    """A file that does not fit its schema; the message is the one line the user reads."""


def _finite_number(checker, x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _integer(checker, x):
    return isinstance(x, int) and not isinstance(x, bool)


_Validator = jsonschema.validators.extend(
    jsonschema.Draft7Validator,
    type_checker=jsonschema.Draft7Validator.TYPE_CHECKER.redefine_many(
        {"number": _finite_number, "integer": _integer}))


@functools.lru_cache(maxsize=None)
def schema(name):
    """The schema `name` (one of NAMES, or specimen_arrays) as a dict."""
    suffix = ".json" if name == "specimen_arrays" else ".schema.json"
    with open(os.path.join(SCHEMAS, name + suffix)) as f:
        return json.load(f)


# The same schemas with no field required: what a reader that takes every field as optional
# checks (the analysis reads a study's metadata.json for what it holds; run_states.py requires it whole).
_Present = jsonschema.validators.extend(_Validator, validators={"required": lambda *args: iter(())})


@functools.lru_cache(maxsize=None)
def _validator(name, required=True):
    store = {schema(n)["$id"]: schema(n) for n in NAMES}
    resolver = jsonschema.RefResolver.from_schema(schema(name), store=store)
    return (_Validator if required else _Present)(schema(name), resolver=resolver)


def _path(error):
    return ".".join(str(p) for p in error.absolute_path)


def _shown(value, most=60):
    if isinstance(value, float) and not math.isfinite(value):
        text = repr(value)
    else:
        try:
            text = json.dumps(value)
        except (TypeError, ValueError):
            text = repr(value)
    return text if len(text) <= most else text[:most - 3] + "..."


_TYPES = {"number": "a finite number", "integer": "an integer", "string": "a text", "object": "a table (JSON object)",
          "array": "a list", "boolean": "true or false", "null": "null"}


def expected(sub):
    """What a (sub)schema asks for, in words: 'a finite number > 0', 'an integer >= 0 or null'."""
    if "const" in sub:
        return _shown(sub["const"])
    if "enum" in sub:
        return "one of " + ", ".join(_shown(v) for v in sub["enum"])
    if "anyOf" in sub:
        return " or ".join(expected(s) for s in sub["anyOf"])
    if "$ref" in sub and "type" not in sub:
        return schema_words(sub)
    types = sub.get("type", [])
    types = [types] if isinstance(types, str) else types
    words = [_TYPES.get(t, t) for t in types]
    bounds = [("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="), ("exclusiveMaximum", "<")]
    limits = " and ".join("%s %s" % (op, _shown(sub[k])) for k, op in bounds if k in sub)
    if limits and words:
        words[0] += " " + limits
    if "pattern" in sub and sub.get("description"):
        return sub["description"]
    return " or ".join(words) or sub.get("description", "what its schema says")


def schema_words(sub):
    return sub.get("description", "what its schema says")


def _what(error):
    v = error.validator
    if v == "required":
        return None
    if v in ("type", "minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum", "enum", "const", "anyOf",
             "pattern"):
        return "must be %s, not %s" % (expected(error.schema), _shown(error.instance))
    if v in ("minItems", "maxItems"):
        return "must have %s %d items, not %d" % ("at least" if v == "minItems" else "at most", error.validator_value,
                                                  len(error.instance))
    return error.message


def problem(instance, name, required=True):
    """The first way `instance` does not fit schema `name`, or None.

    Args:
        instance: the file's content, as json.load gives it.
        name: one of `NAMES` (the schemas of reference/formats).
        required: False checks the fields `instance` holds and requires none.

    Returns:
        (field, what) or None: the field as a dotted path into the file.

    Example:
        >>> from trueaniso import validate
        >>> validate.problem({"E_kinematic": [4.0e8, 3.3e8, 4.5e8]}, "statics_record")
        ('E_blocked', 'missing')
    """
    from .options import flag
    errors = list(_validator(name, flag("validate.problem", "required", required)).iter_errors(instance))
    if not errors:
        return None
    e = jsonschema.exceptions.best_match(errors)
    while e.context:  # anyOf: the reason inside one alternative, when it lies deeper in the file
        deeper = jsonschema.exceptions.best_match(e.context)
        if len(deeper.absolute_path) <= len(e.absolute_path):
            break
        e = deeper
    if e.validator == "required":
        missing = next((k for k in e.validator_value if isinstance(e.instance, dict) and k not in e.instance), "?")
        return ".".join(filter(None, (_path(e), missing))), "missing"
    if e.validator == "propertyNames" or (e.schema_path and "propertyNames" in e.schema_path):
        return str(e.instance), "is not a valid name: %s" % expected(e.schema)
    return _path(e) or "(whole file)", _what(e)


def check(instance, name, file, error=FileInvalid, required=True):
    """`instance` itself when it fits schema `name`; else `error` with one line naming the file and the field.

    Args:
        instance: the file's content, as json.load gives it.
        name: one of `NAMES`.
        file: the file's name, for the message.
        error: the exception class raised (`FileInvalid`).
        required: False checks the fields `instance` holds and requires none.

    Raises:
        FileInvalid: ``<file>: <field>: <what>``.

    Example:
        >>> import json
        >>> from trueaniso import validate
        >>> record = json.load(open("docs/data/spheres-53004-s1/statics_state-21.json"))
        >>> validate.check(record, "statics_record", "statics_state-21.json") is record
        True
        >>> validate.check(dict(record, E_blocked=[3.9e8, -1.0, 4.3e8]), "statics_record", "edited.json")
        Traceback (most recent call last):
        ...
        trueaniso.validate.FileInvalid: edited.json: E_blocked.1: must be a finite number > 0, not -1.0
    """
    found = problem(instance, name, required)
    if found:
        raise error("%s: %s: %s" % (file, *found))
    return instance


def load_json(path, name, error=FileInvalid):
    """The JSON file at `path`, checked against schema `name`.

    Raises:
        FileInvalid: (or `error`) a file that cannot be read, is not JSON or does not fit, in one line.

    Example:
        >>> from trueaniso import validate
        >>> meta = validate.load_json("docs/data/spheres-53004-s1/metadata.json", "study")
        >>> sorted(meta["states"])[:3]
        ['1', '10', '11']
    """
    try:
        with open(path) as f:
            data = json.load(f)
    except OSError as exc:
        raise error("%s: cannot read it (%s)" % (path, exc.strerror)) from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise error("%s: not JSON (%s)" % (path, exc)) from None
    return check(data, name, path, error)


# ------------------------------------------------------------------------ arrays of a specimen file

def _dimension(text, counts):
    if isinstance(text, int):
        return text
    name, _, plus = text.partition("+")
    return None if name not in counts else counts[name] + int(plus or 0)


def arrays_problem(arrays):
    """(array name, what) of the first array of a specimen file that does not fit
    specimen_arrays.json (its kind of number, its shape in the file's counts, finiteness), or
    None. Arrays absent here are the loader's to name (a version has its own set)."""
    import numpy as np
    specs = schema("specimen_arrays")["arrays"]
    counts = {}
    if "positions" in arrays and np.ndim(arrays["positions"]) >= 1:
        counts["nb"] = np.shape(arrays["positions"])[0]
    if "c_member1" in arrays and np.ndim(arrays["c_member1"]) >= 1:
        counts["nc"] = np.shape(arrays["c_member1"])[0]
    for name, spec in specs.items():
        if name not in arrays:
            continue
        a = np.asarray(arrays[name])
        kind = spec["kind"]
        ok = np.issubdtype(a.dtype, np.floating) if kind == "float" else (
            np.issubdtype(a.dtype, np.integer) and not a.dtype == np.bool_)
        if not ok:
            return name, "must hold %s, not %s" % ("floating-point numbers" if kind == "float" else "integers", a.dtype)
        if name == "positions" and a.ndim >= 1 and a.shape[0] == 0:
            return name, "no bodies"
        shape = tuple(_dimension(d, counts) for d in spec["shape"])
        if len(shape) != a.ndim or any(d is not None and d != s for d, s in zip(shape, a.shape)):
            if shape == (3, 3):
                return name, "must be a 3x3 matrix, not of shape %s" % (a.shape,)
            words = "(%s)" % ", ".join(str(d) for d in spec["shape"])
            return name, "has shape %s, not %s" % (a.shape, words.replace("nb", str(counts.get("nb", "nb")))
                                                   .replace("nc", str(counts.get("nc", "nc"))))
        if name == "member_begin" and a.size:
            counts["nm"] = int(a[-1])
        if spec.get("finite") and not np.all(np.isfinite(a)):
            return name, "non-finite values (nan or inf)"
    return None
