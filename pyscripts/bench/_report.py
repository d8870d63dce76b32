"""What every benchmark writes beside its figures: the machine it ran on, and its table in a
Markdown file between the markers <!-- NAME:begin --> and <!-- NAME:end --> (a file without
them gets the block appended), written atomically. A module, not a script."""
import os
import platform
import re


def machine():
    """CPU model, cores, Debian release and platform: the line every benchmark table states."""
    model = platform.machine() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            model = next(ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name"))
    except (OSError, StopIteration):
        pass
    debian = ""
    if os.path.exists("/etc/debian_version"):
        with open("/etc/debian_version") as f:
            debian = ", Debian " + f.read().strip()
    return "%s, %d cores%s, %s" % (model, os.cpu_count(), debian, platform.platform())


def replace_block(path, name, body, heading=None):
    """Put `body` between the NAME markers of the Markdown file `path` (created if missing;
    without markers the block is appended, after `heading` if given). The file is replaced
    atomically: a benchmark interrupted while writing leaves the old file whole."""
    from trueaniso import atomic
    begin, end = "<!-- %s:begin -->" % name, "<!-- %s:end -->" % name
    block = "%s\n%s\n%s" % (begin, body.rstrip("\n"), end)
    text = open(path).read() if os.path.exists(path) else ""
    if begin in text:
        text = re.sub(re.escape(begin) + ".*?" + re.escape(end), lambda _: block, text, flags=re.S)
    else:
        text += "\n" + ("%s\n\n" % heading if heading else "") + block + "\n"
    with atomic.atomic_open(path) as f:
        f.write(text)
