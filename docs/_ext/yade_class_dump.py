"""Run by yade-double (yade_classes.py starts it): the classes named on the command line, as the
loaded YADE plugin documents them, printed as one JSON line after the marker TRUEANISO-YADE-CLASSES.

For each class: its base, its docstring, its own attributes (name, docstring with YADE's
:ydefault: :yattrtype: :yattrflags: roles) and its own methods (name, docstring), in the order YADE
lists them (an instance's dict() gives the attributes in declaration order, bases' after)."""
import json
import sys

import yade.wrapper

out = []
for name in sys.argv[1:]:
    cls = getattr(yade.wrapper, name)
    own = cls.__dict__
    try:
        instance = cls()
        order = list(instance.dict().keys())
    except Exception:  # a class that cannot be made without arguments: its own dict's order
        instance, order = None, []
    names = [a for a in order if a in own] + sorted(a for a in own if a not in order)
    attributes, methods = [], []
    for attr in names:
        if attr.startswith("_"):
            continue
        value = own[attr]
        if isinstance(value, property) or type(value).__name__ == "property":
            try:
                default = repr(getattr(instance, attr)) if instance is not None else None
            except Exception:
                default = None
            attributes.append({"name": attr, "doc": value.__doc__ or "", "value": default})
        elif callable(value):
            methods.append({"name": attr, "doc": value.__doc__ or ""})
    out.append({"name": name, "base": cls.__mro__[1].__name__, "doc": cls.__doc__ or "",
                "attributes": attributes, "methods": methods})
print("TRUEANISO-YADE-CLASSES " + json.dumps(out))
sys.stdout.flush()
