# Region kind "constant": one friction-reduction level over the region
# (0 = no vibration, full friction; 1 = full amplitude). No buffer: the
# level is the region table's value (how K_CONST), rounded half up to uint16.
from ...gen.check import fail, num, check_keys
from . import K_CONST

NAME = "constant"
KEYS = ("kind", "level")
OPTIONS = ()
SHARED = False              # nothing to share: no buffer


def check(path, tex, n):
    check_keys(path, tex, KEYS)
    if "level" not in tex:
        fail(path, "missing required key 'level' (a number in [0.0, 1.0])")
    return {"kind": "constant", "level": num(path + ".level", tex["level"], 0.0, 1.0)}


def amplitude(tex):
    return int(tex["level"] * 65535.0 + 0.5)


def need(tex, n, engine):
    return 0


def block(tex, n, engine):
    return 0


def store(tex, n, engine):
    return K_CONST, amplitude(tex), None


def fill(tex, n, target, engine, dx_um):
    pass


def describe(tex):
    return {"amplitude": amplitude(tex)}


def words(d):
    return "constant %.4f" % (d["amplitude"] / 65535)


def label(d):
    return "constant %.2f" % (d["amplitude"] / 65535)


FIELDS = (("level", "number", 0.0, 1.0, 0.5, "level (friction reduction, 0..1)"),)
