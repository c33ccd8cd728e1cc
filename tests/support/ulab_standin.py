"""A restricted stand-in for ulab 6.x's ``numpy`` module, for CPython tests.

Device code (``device/texel``) reaches ulab only through
``from ulab import numpy`` (``texel.compat.ulab_numpy``). :func:`install` puts
two module objects, ``ulab`` and ``ulab.numpy``, into ``sys.modules`` so that
import works under CPython; :func:`uninstall` (or the :func:`installed`
context manager) takes them out again and restores whatever was there.

What it is for: running the ulab engine on the host with ulab's *interface*
and the ulab semantics that change results, so that a call ulab lacks fails a
test here instead of on a board. Facts below are from ulab's own source
(github.com/v923z/micropython-ulab, ``code/``; 6.0.0 .. 6.12.0):

* namespace (``code/numpy/numpy.c``, ``ulab_numpy_globals_table``): dtypes
  ``bool uint8 int8 uint16 int16 float`` only, and they are *ints* (the
  typecodes ``'?' 'B' 'b' 'H' 'h' 'f'``), not dtype objects; there is no
  ``float32``/``float64``/``int32``/``uint32``; no ``cumsum``, ``repeat``,
  ``searchsorted``. ``numpy.random`` exists from 6.5.0 but SPEC §3 forbids it
  (buggy, differs from numpy): the stand-in refuses it.
* ``float`` is the firmware's ``mp_float_t``: float32 on rp2/stm32 boards.
  Every float array here is float32, and every Python float that meets an
  array is rounded to float32 first (``ndarray_from_mp_obj``).
* scalars in binary operations become one-element arrays of the *smallest*
  dtype (``ndarray_from_mp_obj``: 0..255 -> uint8, 256..65535 -> uint16,
  -128..-1 -> int8, -32768..-129 -> int16, beyond -> float), and the result
  dtype follows ulab's own table (``code/ndarray_operators.c``), e.g.
  uint16 + int16 -> float; integer results wrap.
* ``arange``: int arguments give **int16** (float if any |arg| > 32768); the
  values are accumulated in float (``value += step``) and cast with C
  truncation (``code/numpy/create.c``, ``create_arange``, ``ARANGE_LOOP``).
* float -> integer conversion (``np.array(a, dtype=np.uint16)``, and slice
  assignment of a float array into an integer array, which goes through the
  same ``ndarray_copy_view_convert_type``) **rounds half away from zero**
  (``(int32_t)round(f)``, since ulab 4.4) and then *wraps* into the target
  type (``mp_binary_set_val_array``): 65535.5 stored into uint16 becomes 0.
  A Python *list* of floats with an integer dtype raises TypeError instead
  (``mp_obj_get_int`` of a float).
* in-place ``+= -= *=`` keep the left dtype and refuse a float right operand
  on an integer array; ``/=`` and ``**=`` need a float left operand.
* ``bool(array)`` is ``len(array) != 0`` (ndarray has no BOOL unary op, so
  MicroPython falls back to ``len``): ``if a > 0:`` is always true on ulab.
* ``%`` on arrays exists only from 6.9.0 and was broken until 2026 (#749);
  the ``ndim`` property only from 6.8.0; ``out=`` of the universal functions
  from 6.2.0 and only where ``ULAB_MATH_FUNCTIONS_OUT_KEYWORD`` is set. The
  stand-in refuses all three so device code stays portable to CircuitPython's
  6.5.x.

Limits (what the stand-in does *not* promise):

* It is a strict **subset** of ulab: every name it exposes exists in ulab
  6.x, but many ulab names (fft, linalg, interp, convolve, where, ...) are not
  modelled and raise AttributeError saying so; add them here if device code
  needs them.
* Transcendentals are numpy's float32 kernels, not the board's libm: results
  agree to a few float32 ulps, not bit for bit. Arithmetic on float32 is IEEE
  and matches a board exactly.
* Python-level float arithmetic in device code runs in float64 on CPython
  (float32 on boards); only values that enter an array are rounded.
* No buffer protocol on arrays (Python 3.11 classes cannot export one):
  ``bytes(a)``/``memoryview(a)`` fail here but work on ulab; use
  ``a.tobytes()``.
* Out-of-range float -> int casts (undefined behaviour in C) wrap here.
* 2 dimensions at most (ulab's default ``ULAB_MAX_DIMS``); no complex dtype.

Arrays are a thin wrapper (:class:`ndarray`) over a numpy array so that
numpy-only methods (``astype``, ``sum``, ``cumsum``, ``fill``, ...) are not
there to be relied on by accident. ``numpy.asarray(a)`` / :func:`to_numpy`
is the host-side bridge out.
"""
from __future__ import annotations

import math
import sys
import types
from contextlib import contextmanager
from typing import Any, Iterator

import numpy as _np

__all__ = ["install", "uninstall", "installed", "is_installed", "to_numpy", "ndarray",
           "VERSION", "ULAB", "NUMPY"]

VERSION = "6.12.0-standin"

# ulab's dtypes are the typecodes of code/ndarray.h (enum NDARRAY_TYPE), as ints.
BOOL = ord("?")
UINT8 = ord("B")
INT8 = ord("b")
UINT16 = ord("H")
INT16 = ord("h")
FLOAT = ord("f")            # 'f': MICROPY_FLOAT_IMPL_FLOAT (boards); 'd' on double builds

_NP_TYPE: dict[int, Any] = {BOOL: _np.bool_, UINT8: _np.uint8, INT8: _np.int8,
                            UINT16: _np.uint16, INT16: _np.int16, FLOAT: _np.float32}
_NAME = {BOOL: "bool", UINT8: "uint8", INT8: "int8", UINT16: "uint16", INT16: "int16",
         FLOAT: "float32"}
_INT_CODES = (UINT8, INT8, UINT16, INT16)
MAX_DIMS = 2
_F32 = _np.float32


# ----------------------------------------------------------------------------
# scalars and conversions

def _is_bool(x: Any) -> bool:
    return isinstance(x, (bool, _np.bool_))


def _is_int(x: Any) -> bool:
    return isinstance(x, (int, _np.integer)) and not _is_bool(x)


def _is_float(x: Any) -> bool:
    # numpy float scalars count as floats so that tests can emulate a float32
    # interpreter (np.float32 constants); on a board these are Python floats.
    return isinstance(x, (float, _np.floating))


def _check_dtype(dtype: Any) -> int:
    if _is_bool(dtype) or not _is_int(dtype):
        # ulab: mp_obj_get_int(dtype) -> TypeError for anything but an int.
        raise TypeError("ulab dtype must be one of numpy.bool/uint8/int8/uint16/int16/float"
                        " (ints), got %r" % (dtype,))
    dtype = int(dtype)
    if dtype not in _NP_TYPE:
        raise ValueError("ulab has no dtype with code %r" % (dtype,))
    return dtype


def _wrap_int(values: _np.ndarray, code: int) -> _np.ndarray:
    """Store integers into a 16/8-bit type the way C does: modulo 2^bits."""
    return _np.asarray(values).astype(_np.int64).astype(_NP_TYPE[code])


def _float_to_int(values: _np.ndarray, code: int) -> _np.ndarray:
    """ulab's float -> integer conversion: (int32_t)round(f), half away from
    zero, then wrapped into the target type (ndarray_copy_view_convert_type)."""
    v = _np.asarray(values, dtype=_np.float64)
    r = _np.where(_np.isfinite(v), _np.sign(v) * _np.floor(_np.abs(v) + 0.5), 0.0)
    return _wrap_int(r, code)


def _convert(a: _np.ndarray, src: int, dst: int) -> _np.ndarray:
    """Copy of a (ulab dtype src) as ulab dtype dst."""
    if src == dst:
        return a.copy()
    if dst == BOOL:
        return a != 0
    if dst == FLOAT:
        return a.astype(_np.float32)
    if src == FLOAT:
        return _float_to_int(a, dst)
    return _wrap_int(a, dst)


def _pyscalar(x: Any, code: int) -> Any:
    if code == FLOAT:
        return float(x)
    if code == BOOL:
        return bool(x)
    return int(x)


def _scalar_array(obj: Any, other: int | None) -> ndarray:
    """ndarray_from_mp_obj: a scalar as a one-element array of the smallest dtype."""
    if isinstance(obj, ndarray):
        return obj
    if _is_bool(obj):
        return ndarray._new(_np.array([bool(obj)]), BOOL)
    if _is_int(obj):
        v = int(obj)
        if v < -32768 or v > 65535:
            return ndarray._new(_np.array([v], dtype=_np.float32), FLOAT)
        if v < 0:
            code = INT8 if v >= -128 else INT16
        elif other in (INT8, INT16):
            code = INT8 if v < 128 else INT16
        else:
            code = UINT8 if v < 256 else UINT16
        return ndarray._new(_np.array([v], dtype=_NP_TYPE[code]), code)
    if _is_float(obj):
        return ndarray._new(_np.array([obj], dtype=_np.float32), FLOAT)
    if isinstance(obj, complex):
        raise TypeError("the ulab stand-in has no complex dtype")
    # any other iterable becomes a float array (ndarray_from_iterable(obj, FLOAT))
    return _from_iterable(obj, FLOAT)


def _from_iterable(obj: Any, code: int) -> ndarray:
    try:
        rows = list(obj)
    except TypeError:
        raise TypeError("can't convert %s to an ulab array" % type(obj).__name__) from None
    nested = bool(rows) and not isinstance(rows[0], (str, bytes)) and _iterable(rows[0])
    if nested:
        rows = [list(r) for r in rows]
        if len({len(r) for r in rows}) > 1:
            raise ValueError("ulab: rows of different lengths")
        flat = [x for r in rows for x in r]
        shape: tuple[int, ...] = (len(rows), len(rows[0]))
    else:
        flat = rows
        shape = (len(rows),)
    for x in flat:
        if _iterable(x):
            raise ValueError("too many dimensions (ulab stand-in: at most %d)" % MAX_DIMS)
    out = _np.zeros(len(flat), dtype=_NP_TYPE[code])
    for i, x in enumerate(flat):
        out[i] = _set_value(x, code)
    return ndarray._new(out.reshape(shape), code)


def _iterable(x: Any) -> bool:
    if isinstance(x, ndarray):
        return True
    try:
        iter(x)
    except TypeError:
        return False
    return True


def _set_value(x: Any, code: int) -> Any:
    """mp_binary_set_val_array for one Python object (array(list) path)."""
    if code == BOOL:
        return bool(x)
    if code == FLOAT:
        if not (_is_float(x) or _is_int(x) or _is_bool(x)):
            raise TypeError("can't convert %s to float" % type(x).__name__)
        return _np.float32(float(x))
    if _is_float(x):
        # mp_obj_get_int(float) raises in MicroPython
        raise TypeError("can't convert float to int")
    if not (_is_int(x) or _is_bool(x)):
        raise TypeError("can't convert %s to int" % type(x).__name__)
    return _wrap_int(_np.array([int(x)]), code)[0]


# ----------------------------------------------------------------------------
# the result dtype of binary operations (code/ndarray_operators.c)

def _ab(t: dict[tuple[int, int], int]) -> dict[frozenset[int], int]:
    return {frozenset(k): v for k, v in t.items()}


# + - * & | ^ (ndarray_binary_add/subtract/multiply/logical): symmetric
_ADD = _ab({(UINT8, INT8): INT16, (UINT8, UINT16): UINT16, (UINT8, INT16): INT16,
            (INT8, UINT16): INT16, (INT8, INT16): INT16, (UINT16, INT16): FLOAT})
# // (ndarray_binary_floor_divide): as +, except int8 with uint16 -> uint16
_FLOORDIV = dict(_ADD)
_FLOORDIV[frozenset((INT8, UINT16))] = UINT16


def _result_dtype(op: str, lt: int, rt: int) -> int:
    lt = UINT8 if lt == BOOL else lt       # Boolean arrays are uint8 with a flag
    rt = UINT8 if rt == BOOL else rt
    if op in ("truediv", "pow"):
        return FLOAT
    if lt == rt:
        return lt
    if FLOAT in (lt, rt):
        return FLOAT
    table = _FLOORDIV if op == "floordiv" else _ADD
    return table[frozenset((lt, rt))]


_OPS = {"add": _np.add, "sub": _np.subtract, "mul": _np.multiply,
        "truediv": _np.true_divide, "floordiv": _np.floor_divide, "pow": _np.power,
        "and": _np.bitwise_and, "or": _np.bitwise_or, "xor": _np.bitwise_xor}
_CMP = {"lt": _np.less, "le": _np.less_equal, "gt": _np.greater, "ge": _np.greater_equal,
        "eq": _np.equal, "ne": _np.not_equal}


def _operands(lobj: Any, robj: Any) -> tuple[ndarray, ndarray]:
    lhs = _scalar_array(lobj, None)
    rhs = _scalar_array(robj, lhs._dt)
    return lhs, rhs


def _binary(op: str, lobj: Any, robj: Any) -> ndarray:
    lhs, rhs = _operands(lobj, robj)
    code = _result_dtype(op, lhs._dt, rhs._dt)
    if op in ("and", "or", "xor") and code == FLOAT:
        raise TypeError("ulab: bitwise operations are not defined for float arrays")
    la, ra = lhs._a, rhs._a
    with _np.errstate(all="ignore"):
        if code == FLOAT:
            if op == "floordiv":
                r = _np.floor(la.astype(_np.float32) / ra.astype(_np.float32))
            else:
                r = _OPS[op](la.astype(_np.float32), ra.astype(_np.float32))
            r = _np.asarray(r, dtype=_np.float32)
        else:
            # C arithmetic on promoted ints, then stored into the result type
            li, ri = la.astype(_np.int64), ra.astype(_np.int64)
            if op == "floordiv":
                r = _np.where(ri == 0, 0, _np.floor_divide(li, _np.where(ri == 0, 1, ri)))
            else:
                r = _OPS[op](li, ri)
            r = _wrap_int(r, code)
    return ndarray._new(_np.asarray(r), code)


def _compare(op: str, lobj: Any, robj: Any) -> ndarray:
    lhs, rhs = _operands(lobj, robj)
    return ndarray._new(_np.asarray(_CMP[op](lhs._a, rhs._a)), BOOL)


# ----------------------------------------------------------------------------
# ndarray

_NUMPY_ONLY_METHODS = {
    "astype": "use numpy.array(a, dtype=...)",
    "sum": "use numpy.sum(a)", "mean": "use numpy.mean(a)", "std": "use numpy.std(a)",
    "min": "use numpy.min(a)", "max": "use numpy.max(a)",
    "argmin": "use numpy.argmin(a)", "argmax": "use numpy.argmax(a)",
    "cumsum": "ulab has no cumsum", "repeat": "ulab has no repeat",
    "searchsorted": "ulab has no searchsorted", "fill": "use a[:] = value",
    "ndim": "the ndim property exists only from ulab 6.8.0: use len(a.shape)",
    "item": "use a[i]", "view": "ulab has no view(); slices are views",
    "ravel": "use a.flatten()", "clip": "use numpy.clip(a, lo, hi)",
    "round": "use numpy.around(a)", "dot": "numpy.dot (2-D builds only)",
    "nbytes": "use a.size * a.itemsize",
}


class ndarray:
    """ulab.numpy.ndarray stand-in: 1 or 2 dimensions, ulab dtypes only."""

    __slots__ = ("_a", "_dt")
    __hash__ = None  # type: ignore[assignment]

    def __init__(self, values: Any, dtype: int = FLOAT) -> None:
        made = array(values, dtype=dtype)
        self._a = made._a
        self._dt = made._dt

    @classmethod
    def _new(cls, a: _np.ndarray, code: int) -> ndarray:
        if a.ndim > MAX_DIMS:
            raise ValueError("maximum number of dimensions is %d" % MAX_DIMS)
        self = object.__new__(cls)
        self._a = a
        self._dt = code
        return self

    # --- properties (code/ndarray_properties.c) ---
    @property
    def dtype(self) -> int:
        # Boolean arrays carry dtype uint8 plus a flag: ndarray_dtype returns uint8.
        return UINT8 if self._dt == BOOL else self._dt

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(int(s) for s in self._a.shape)

    @property
    def size(self) -> int:
        return int(self._a.size)

    @property
    def itemsize(self) -> int:
        return int(self._a.itemsize)

    @property
    def strides(self) -> tuple[int, ...]:
        return tuple(int(s) for s in self._a.strides)

    @property
    def T(self) -> ndarray:
        return ndarray._new(self._a.T, self._dt)

    @property
    def flat(self) -> Iterator[Any]:
        return (_pyscalar(x, self._dt) for x in self._a.reshape(-1))

    # --- methods (ulab_ndarray_locals_dict_table in code/ulab.c) ---
    def copy(self) -> ndarray:
        return ndarray._new(self._a.copy(), self._dt)

    def flatten(self, order: str = "C") -> ndarray:
        if order not in ("C", "F"):
            raise ValueError("flattening order must be either 'C', or 'F'")
        return ndarray._new(self._a.flatten(order=order), self._dt)

    def tobytes(self) -> bytes:
        return self._a.tobytes()

    def tolist(self) -> list[Any]:
        if self._a.ndim == 1:
            return [_pyscalar(x, self._dt) for x in self._a]
        return [[_pyscalar(x, self._dt) for x in row] for row in self._a]

    def sort(self, axis: int | None = -1) -> None:
        if axis is None:
            raise TypeError("ulab: in-place sort needs an axis")
        self._a.sort(axis=axis)

    def reshape(self, shape: Any) -> ndarray:
        if _is_int(shape):
            shape = (int(shape),)
        shape = tuple(shape)
        if len(shape) > MAX_DIMS:
            raise ValueError("maximum number of dimensions is %d" % MAX_DIMS)
        return ndarray._new(self._a.reshape(shape), self._dt)

    def transpose(self) -> ndarray:
        return ndarray._new(self._a.T, self._dt)

    def byteswap(self, inplace: bool = False) -> ndarray:
        if inplace:
            self._a.byteswap(inplace=True)
            return self
        return ndarray._new(self._a.byteswap(), self._dt)

    # --- numpy-only names: refuse them loudly ---
    def __getattr__(self, name: str) -> Any:
        hint = _NUMPY_ONLY_METHODS.get(name)
        if hint is not None:
            raise AttributeError("ulab ndarray has no attribute %r (%s)" % (name, hint))
        raise AttributeError("ulab ndarray has no attribute %r" % (name,))

    # --- host bridge (not a ulab feature; numpy does not exist on a board) ---
    def __array__(self, dtype: Any = None, copy: Any = None) -> _np.ndarray:
        a = self._a.copy()
        return a if dtype is None else a.astype(dtype)

    # --- container protocol ---
    def __len__(self) -> int:
        if self._a.ndim == 0:
            return 0
        return int(self._a.shape[0])

    def __bool__(self) -> bool:
        # MicroPython falls back to len() for truthiness: never elementwise.
        return len(self) != 0

    def __iter__(self) -> Iterator[Any]:
        if self._a.ndim == 1:
            for x in self._a:
                yield _pyscalar(x, self._dt)
        else:
            for i in range(self._a.shape[0]):
                yield ndarray._new(self._a[i], self._dt)

    def _index(self, index: Any) -> Any:
        if isinstance(index, ndarray):
            if index._dt != BOOL or index._a.ndim != 1:
                raise NotImplementedError("operation is implemented for 1D Boolean arrays only")
            if index.size != self._a.shape[0]:
                raise ValueError("array and index length must be equal")
            return index._a
        items = index if isinstance(index, tuple) else (index,)
        if len(items) > self._a.ndim:
            raise IndexError("too many indices")
        for it in items:
            if isinstance(it, slice):
                for part in (it.start, it.stop, it.step):
                    if part is not None and not _is_int(part):
                        raise TypeError("slice indices must be integers or None")
            elif not _is_int(it):
                raise IndexError("indices must be integers, slices, or Boolean lists")
        return index

    def __getitem__(self, index: Any) -> Any:
        idx = self._index(index)
        try:
            r = self._a[idx]
        except IndexError:
            raise IndexError("index is out of bounds") from None
        if isinstance(r, _np.ndarray) and r.ndim > 0:
            return ndarray._new(r, self._dt)    # basic slicing: a view, as in ulab
        return _pyscalar(r, self._dt)

    def __setitem__(self, index: Any, value: Any) -> None:
        idx = self._index(index)
        values = _scalar_array(value, None)       # ndarray_from_mp_obj(value, 0)
        conv = _convert(values._a, values._dt, self._dt)
        try:
            target = self._a[idx]
        except IndexError:
            raise IndexError("index is out of bounds") from None
        try:
            if _np.ndim(target) == 0:
                if conv.size != 1:
                    raise ValueError
                self._a[idx] = conv.reshape(-1)[0]
            else:
                self._a[idx] = _np.broadcast_to(conv, _np.shape(target))
        except ValueError:
            raise ValueError("operands could not be broadcast together") from None

    def __delitem__(self, index: Any) -> None:
        raise ValueError("cannot delete array elements")

    # --- arithmetic ---
    def __add__(self, o: Any) -> ndarray:
        return _binary("add", self, o)

    # Reversed operators: ulab's ndarray_binary_op makes the scalar the left
    # operand, with the smallest dtype regardless of the array's (other_type
    # 0): 5 + int8_array is uint8 + int8 -> int16, int8_array + 5 stays int8.
    def __radd__(self, o: Any) -> ndarray:
        return _binary("add", o, self)

    def __sub__(self, o: Any) -> ndarray:
        return _binary("sub", self, o)

    def __rsub__(self, o: Any) -> ndarray:
        return _binary("sub", o, self)

    def __mul__(self, o: Any) -> ndarray:
        return _binary("mul", self, o)

    def __rmul__(self, o: Any) -> ndarray:
        return _binary("mul", o, self)

    def __truediv__(self, o: Any) -> ndarray:
        return _binary("truediv", self, o)

    def __rtruediv__(self, o: Any) -> ndarray:
        return _binary("truediv", o, self)

    def __floordiv__(self, o: Any) -> ndarray:
        return _binary("floordiv", self, o)

    def __rfloordiv__(self, o: Any) -> ndarray:
        raise TypeError("ulab has no reversed floor division (scalar // ndarray)")

    def __pow__(self, o: Any) -> ndarray:
        return _binary("pow", self, o)

    def __rpow__(self, o: Any) -> ndarray:
        return _binary("pow", o, self)

    def __mod__(self, o: Any) -> ndarray:
        raise TypeError("ndarray %: only from ulab 6.9.0 and broken until #749 (2026); "
                        "not portable to ulab 6.x boards")

    __rmod__ = __mod__

    def __imod__(self, o: Any) -> ndarray:
        raise TypeError("ndarray %=: compiled out of ulab before #749 (2026); not portable")

    def __and__(self, o: Any) -> ndarray:
        return _binary("and", self, o)

    def __or__(self, o: Any) -> ndarray:
        return _binary("or", self, o)

    def __xor__(self, o: Any) -> ndarray:
        return _binary("xor", self, o)

    def __matmul__(self, o: Any) -> ndarray:
        raise TypeError("ulab has no @ operator (numpy.dot exists on 2-D builds)")

    def _inplace(self, op: str, o: Any) -> ndarray:
        rhs = _scalar_array(o, self._dt)
        if op in ("truediv", "pow") and self._dt != FLOAT:
            raise TypeError("results cannot be cast to specified type")
        if self._dt != FLOAT and rhs._dt == FLOAT:
            raise TypeError("cannot cast output with casting rule")
        try:
            _np.broadcast_to(rhs._a, self._a.shape)
        except ValueError:
            raise ValueError("operands could not be broadcast together") from None
        with _np.errstate(all="ignore"):
            if self._dt == FLOAT:
                r = _OPS[op](self._a, rhs._a.astype(_np.float32))
                self._a[...] = _np.asarray(r, dtype=_np.float32)
            else:
                r = _OPS[op](self._a.astype(_np.int64), rhs._a.astype(_np.int64))
                self._a[...] = _wrap_int(r, self._dt)
        return self

    def __iadd__(self, o: Any) -> ndarray:
        return self._inplace("add", o)

    def __isub__(self, o: Any) -> ndarray:
        return self._inplace("sub", o)

    def __imul__(self, o: Any) -> ndarray:
        return self._inplace("mul", o)

    def __itruediv__(self, o: Any) -> ndarray:
        return self._inplace("truediv", o)

    def __ipow__(self, o: Any) -> ndarray:
        return self._inplace("pow", o)

    def __ifloordiv__(self, o: Any) -> ndarray:
        raise TypeError("ulab has no in-place floor division")

    def __lt__(self, o: Any) -> ndarray:
        return _compare("lt", self, o)

    def __le__(self, o: Any) -> ndarray:
        return _compare("le", self, o)

    def __gt__(self, o: Any) -> ndarray:
        return _compare("gt", self, o)

    def __ge__(self, o: Any) -> ndarray:
        return _compare("ge", self, o)

    def __eq__(self, o: Any) -> ndarray:  # type: ignore[override]
        return _compare("eq", self, o)

    def __ne__(self, o: Any) -> ndarray:  # type: ignore[override]
        return _compare("ne", self, o)

    def __neg__(self) -> ndarray:
        if self._dt == FLOAT:
            return ndarray._new(-self._a, FLOAT)
        return ndarray._new(_wrap_int(-self._a.astype(_np.int64), self._dt), self._dt)

    def __pos__(self) -> ndarray:
        return self.copy()

    def __abs__(self) -> ndarray:
        if self._dt == FLOAT:
            return ndarray._new(_np.abs(self._a), FLOAT)
        return ndarray._new(_wrap_int(_np.abs(self._a.astype(_np.int64)), self._dt), self._dt)

    def __invert__(self) -> ndarray:
        if self._dt == FLOAT:
            raise TypeError("operation is not supported for given type")
        if self._dt == BOOL:
            return ndarray._new(~self._a, BOOL)
        return ndarray._new(~self._a, self._dt)

    def __repr__(self) -> str:
        body = ", ".join(repr(x) for x in self.tolist())
        return "array([%s], dtype=%s)" % (body, _NAME[self._dt])

    __str__ = __repr__


def to_numpy(a: ndarray) -> _np.ndarray:
    """A numpy copy of a stand-in array (host-side bridge; float32 for float)."""
    if not isinstance(a, ndarray):
        raise TypeError("expected a ulab stand-in ndarray, got %s" % type(a).__name__)
    return a._a.copy()


# ----------------------------------------------------------------------------
# module functions (names of ulab_numpy_globals_table)

def array(values: Any, *, dtype: int = FLOAT) -> ndarray:
    code = _check_dtype(dtype)
    if isinstance(values, ndarray):
        # ndarray_copy_view_convert_type: always a dense copy
        return ndarray._new(_convert(values._a, values._dt, code), code)
    return _from_iterable(values, code)


def _args_float(*xs: Any) -> list[Any]:
    out = []
    for x in xs:
        if not (_is_int(x) or _is_float(x) or _is_bool(x)):
            raise TypeError("can't convert %s to float" % type(x).__name__)
        out.append(_F32(float(x)))
    return out


def _ramp(start: Any, step: Any, stop: Any, n: int, code: int) -> ndarray:
    """create_linspace_arange: value += step in mp_float_t, the last = stop,
    stored with a C cast (truncation toward zero for integer types)."""
    if n == 0:
        return ndarray._new(_np.zeros(0, dtype=_NP_TYPE[code]), code)
    seq = _np.full(n, step, dtype=_np.float32)
    seq[0] = start
    vals = _np.cumsum(seq, dtype=_np.float32)   # sequential float32 accumulation
    vals[-1] = stop
    if code == FLOAT:
        return ndarray._new(vals, FLOAT)
    if code == BOOL:
        return ndarray._new(vals != 0, BOOL)
    return ndarray._new(_wrap_int(_np.trunc(vals.astype(_np.float64)), code), code)


def arange(*args: Any, dtype: int | None = None) -> ndarray:
    if not 1 <= len(args) <= 3:
        raise TypeError("wrong number of arguments")
    if len(args) == 1:
        start, stop, step = 0, args[0], 1
    elif len(args) == 2:
        start, stop, step = args[0], args[1], 1
    else:
        start, stop, step = args
    code = INT16 if all(_is_int(a) for a in args) else FLOAT
    fstart, fstop, fstep = _args_float(start, stop, step)
    if abs(fstop) > 32768 or abs(fstart) > 32768 or abs(fstep) > 32768:
        code = FLOAT
    if dtype is not None:
        code = _check_dtype(dtype)
    if fstep == 0:
        raise ZeroDivisionError("divide by zero")
    if not (math.isfinite(fstart) and math.isfinite(fstop) and math.isfinite(fstep)):
        raise ValueError("arange: cannot compute length")
    ratio = (fstop - fstart) / fstep
    if ratio <= 0:
        return ndarray._new(_np.zeros(0, dtype=_NP_TYPE[code]), code)
    n = int(math.ceil(ratio))
    last = _F32(fstart + _F32(n - 1) * fstep)
    return _ramp(fstart, fstep, last, n, code)


def linspace(start: Any, stop: Any, num: int = 50, *, endpoint: bool = True,
             retstep: bool = False, dtype: int = FLOAT) -> Any:
    code = _check_dtype(dtype)
    if num < 2:
        raise ValueError("number of points must be at least 2")
    fstart, fstop = _args_float(start, stop)
    if endpoint:
        step = _F32((fstop - fstart) / _F32(num - 1))
    else:
        step = _F32((fstop - fstart) / _F32(num))
        fstop = _F32(fstart + step * _F32(num - 1))
    out = _ramp(fstart, step, fstop, num, code)
    return (out, float(step)) if retstep else out


def _shape(shape: Any) -> tuple[int, ...]:
    if _is_int(shape):
        return (int(shape),)
    if isinstance(shape, (tuple, list)):
        if len(shape) > MAX_DIMS:
            raise TypeError("too many dimensions")
        return tuple(int(s) for s in shape)
    raise TypeError("input argument must be an integer, a tuple, or a list")


def zeros(shape: Any, *, dtype: int = FLOAT) -> ndarray:
    code = _check_dtype(dtype)
    return ndarray._new(_np.zeros(_shape(shape), dtype=_NP_TYPE[code]), code)


def empty(shape: Any, *, dtype: int = FLOAT) -> ndarray:
    # ulab's empty is zeros (create_zeros_obj)
    return zeros(shape, dtype=dtype)


def full(shape: Any, fill_value: Any, *, dtype: int = FLOAT) -> ndarray:
    code = _check_dtype(dtype)
    out = zeros(shape, dtype=code)
    if code == BOOL:
        out._a[...] = bool(fill_value)
    else:
        out._a[...] = _set_value(fill_value, code)
    return out


def ones(shape: Any, *, dtype: int = FLOAT) -> ndarray:
    return full(shape, 1, dtype=dtype)


def concatenate(arrays: Any, *, axis: int = 0) -> ndarray:
    if not isinstance(arrays, tuple):
        raise TypeError("first argument must be a tuple of ndarrays")
    for a in arrays:
        if not isinstance(a, ndarray):
            raise ValueError("only ndarrays can be concatenated")
    code = arrays[0]._dt
    for a in arrays:
        if a._dt != code:
            raise TypeError("the stand-in concatenates arrays of one dtype only")
    return ndarray._new(_np.concatenate([a._a for a in arrays], axis=axis), code)


def frombuffer(buffer: Any, *, dtype: int = FLOAT, count: int = -1, offset: int = 0) -> ndarray:
    """Shares the buffer's memory, as ulab does (create_frombuffer passes the
    buffer pointer to the new array). A read-only buffer (bytes) gives a
    read-only array here; ulab would write into it regardless."""
    code = _check_dtype(dtype)
    if code == BOOL:
        raise TypeError("the stand-in has no Boolean frombuffer")
    a = _np.frombuffer(buffer, dtype=_NP_TYPE[code], count=count, offset=offset)
    return ndarray._new(a, code)


def _as_array(x: Any) -> ndarray:
    if isinstance(x, ndarray):
        return x
    if _iterable(x):
        return _from_iterable(x, FLOAT)
    raise TypeError("input must be an ndarray, or an iterable")


def _ufunc(name: str, f: Any) -> Any:
    def fn(x: Any, **kw: Any) -> Any:
        if "out" in kw:
            raise TypeError("%s(out=...): only from ulab 6.2.0 and only with "
                            "ULAB_MATH_FUNCTIONS_OUT_KEYWORD; not portable" % name)
        if kw:
            raise TypeError("unexpected keyword argument %r" % next(iter(kw)))
        if _is_int(x) or _is_float(x):
            # a Python float (float32 on boards) in, a float out
            with _np.errstate(all="ignore"):
                return float(f(_F32(float(x))))
        src = _scalar_array(x, None) if not isinstance(x, ndarray) else x
        if src._dt == BOOL:
            src = ndarray._new(src._a.astype(_np.uint8), UINT8)
        with _np.errstate(all="ignore"):
            r = f(src._a.astype(_np.float32))
        return ndarray._new(_np.asarray(r, dtype=_np.float32), FLOAT)
    fn.__name__ = name
    fn.__doc__ = "ulab.numpy.%s: float in, float out (float32); no out= keyword." % name
    return fn


_UFUNCS = {
    "sin": _np.sin, "cos": _np.cos, "tan": _np.tan,
    "asin": _np.arcsin, "acos": _np.arccos, "atan": _np.arctan,
    "sinh": _np.sinh, "cosh": _np.cosh, "tanh": _np.tanh,
    "asinh": _np.arcsinh, "acosh": _np.arccosh, "atanh": _np.arctanh,
    "exp": _np.exp, "expm1": _np.expm1, "log": _np.log, "log10": _np.log10,
    "log2": _np.log2, "sqrt": _np.sqrt, "degrees": _np.degrees, "radians": _np.radians,
}


def _axis_reduce(a: ndarray, axis: int | None) -> tuple[_np.ndarray, bool]:
    if axis is None:
        return a._a.reshape(-1), True
    return _np.moveaxis(a._a, axis, 0), False


def _running_mean(a: ndarray, axis: int | None) -> tuple[Any, Any, int]:
    """numerical_sum_mean_std_ndarray: m = M + (v - M)/count in mp_float_t."""
    data, flat = _axis_reduce(a, axis)
    data = data.astype(_np.float32)
    M = _np.zeros(data.shape[1:], dtype=_np.float32)
    S = _np.zeros(data.shape[1:], dtype=_np.float32)
    for count, v in enumerate(data, start=1):
        m = M + (v - M) / _F32(count)
        S = S + (v - M) * (v - m)
        M = m
    return M, S, len(data)


def _sum(a: Any, axis: int | None = None) -> Any:
    a = _as_array(a)
    M, _, n = _running_mean(a, axis)
    total = _np.float32(M * _F32(n))
    if axis is None:
        if a._dt == FLOAT:
            return float(total)
        t = float(total)      # (int32_t)round(M * len): half away from zero
        return int(math.copysign(math.floor(abs(t) + 0.5), t))
    if a._dt == FLOAT:
        return ndarray._new(_np.asarray(total, dtype=_np.float32), FLOAT)
    return ndarray._new(_float_to_int(total, a._dt), a._dt)


def _mean(a: Any, axis: int | None = None) -> Any:
    a = _as_array(a)
    M, _, _ = _running_mean(a, axis)
    return float(M) if axis is None else ndarray._new(_np.asarray(M, dtype=_np.float32), FLOAT)


def _std(a: Any, axis: int | None = None, *, ddof: int = 0) -> Any:
    a = _as_array(a)
    M, S, n = _running_mean(a, axis)
    if ddof > n:
        return 0.0
    r = _np.sqrt(S / _F32(n - ddof)).astype(_np.float32)
    return float(r) if axis is None else ndarray._new(_np.asarray(r), FLOAT)


def _minmax(name: str, f: Any, arg: bool) -> Any:
    def fn(a: Any, axis: int | None = None) -> Any:
        a = _as_array(a)
        if a.size == 0:
            raise ValueError("attempt to get %s of an empty sequence" % name)
        if axis is None:
            r = f(a._a.reshape(-1))
            return int(r) if arg else _pyscalar(r, a._dt)
        r = f(a._a, axis=axis)
        if arg:
            return ndarray._new(r.astype(_np.uint16), UINT16)
        return ndarray._new(r, a._dt)
    fn.__name__ = name
    return fn


def clip(a: Any, a_min: Any, a_max: Any) -> ndarray:
    return minimum(maximum(a, a_min), a_max)


def maximum(x1: Any, x2: Any) -> ndarray:
    lhs, rhs = _operands(x1, x2)
    code = _result_dtype("add", lhs._dt, rhs._dt)
    r = _np.maximum(_convert(lhs._a, lhs._dt, code), _convert(rhs._a, rhs._dt, code))
    return ndarray._new(_np.asarray(r), code)


def minimum(x1: Any, x2: Any) -> ndarray:
    lhs, rhs = _operands(x1, x2)
    code = _result_dtype("add", lhs._dt, rhs._dt)
    r = _np.minimum(_convert(lhs._a, lhs._dt, code), _convert(rhs._a, rhs._dt, code))
    return ndarray._new(_np.asarray(r), code)


def sort(a: Any, *, axis: int | None = -1) -> ndarray:
    a = _as_array(a)
    if axis is None:
        return ndarray._new(_np.sort(a._a.reshape(-1)), a._dt)
    return ndarray._new(_np.sort(a._a, axis=axis), a._dt)


def argsort(a: Any, *, axis: int | None = -1) -> ndarray:
    a = _as_array(a)
    src = a._a.reshape(-1) if axis is None else a._a
    r = _np.argsort(src, axis=-1 if axis is None else axis, kind="stable")
    return ndarray._new(r.astype(_np.uint16), UINT16)


def flip(a: Any, *, axis: int | None = None) -> ndarray:
    a = _as_array(a)
    return ndarray._new(_np.flip(a._a, axis=axis).copy(), a._dt)


# ----------------------------------------------------------------------------
# the module objects

# In ulab 6.x but not modelled here: AttributeError says so (add them here
# when device code needs them, with their ulab semantics).
IN_ULAB_NOT_MODELLED = frozenset("""
    fft linalg ndinfo set_printoptions get_printoptions compress delete diag eye
    interp trapz logspace meshgrid bincount equal not_equal isfinite isinf nonzero
    where bitwise_and bitwise_or bitwise_xor left_shift right_shift convolve all any
    asarray cross diff dot trace load loadtxt save savetxt median roll size take
    polyfit polyval arctan2 around ceil floor sinc vectorize complex real imag
    conjugate sort_complex
""".split())

# Names numpy has and ulab 6.x does not, with what to do instead.
ULAB_LACKS: dict[str, str] = {
    "cumsum": "ulab has no cumsum (SPEC §3): accumulate in integers or chunk",
    "cumprod": "ulab has no cumprod",
    "repeat": "ulab has no repeat (SPEC §3)",
    "searchsorted": "ulab has no searchsorted (SPEC §3)",
    "random": "numpy.random: buggy in ulab 6.x (size must be a tuple, odd sizes overrun) "
              "and absent before 6.5.0; SPEC §3 forbids it - use texel.gen.rng",
    "float32": "ulab's only float dtype is numpy.float (float32 on boards)",
    "float64": "no float64 in ulab: numpy.float is float32 on boards",
    "float16": "ulab has no float16", "double": "no float64 in ulab",
    "int32": "no int32 in ulab: dtypes are bool/uint8/int8/uint16/int16/float",
    "uint32": "no uint32 in ulab: dtypes are bool/uint8/int8/uint16/int16/float",
    "int64": "no int64 in ulab", "uint64": "no uint64 in ulab",
    "complex64": "no complex64 in ulab", "complex128": "no complex128 in ulab",
    "dtype": "ulab.numpy has no dtype class (ulab.dtype is a top-level function)",
    "astype": "use numpy.array(a, dtype=...)",
    "round": "ulab spells it numpy.around", "abs": "use the builtin abs(a)",
    "absolute": "use the builtin abs(a)", "arcsin": "ulab spells it numpy.asin",
    "arccos": "ulab spells it numpy.acos", "arctan": "ulab spells it numpy.atan",
    "empty_like": "ulab has no *_like constructors", "zeros_like": "ulab has no *_like",
    "ones_like": "ulab has no *_like", "full_like": "ulab has no *_like",
    "isnan": "ulab has isfinite/isinf only", "prod": "ulab has no prod",
    "unique": "ulab has no unique", "histogram": "ulab has no histogram",
    "append": "use numpy.concatenate((a, b))", "stack": "ulab has no stack",
    "hstack": "use numpy.concatenate", "vstack": "use numpy.concatenate",
    "tile": "ulab has no tile", "outer": "ulab has no outer", "matmul": "ulab has no matmul",
    "add": "use the + operator", "multiply": "use the * operator",
    "subtract": "use the - operator", "divide": "use the / operator",
    "floor_divide": "use the // operator", "mod": "ulab has no mod function",
    "remainder": "ulab has no remainder function", "fmod": "ulab has no fmod",
    "power": "use the ** operator", "hypot": "ulab has no hypot", "sign": "ulab has no sign",
    "rint": "use numpy.around", "trunc": "ulab has no trunc", "var": "use numpy.std",
    "average": "ulab has no average", "percentile": "ulab has no percentile",
    "reshape": "use a.reshape(shape)", "ravel": "use a.flatten()",
    "transpose": "use a.transpose() / a.T", "shape": "use a.shape",
    "ndim": "use len(a.shape)", "newaxis": "ulab has no newaxis",
    "errstate": "ulab has no errstate", "seterr": "ulab has no seterr",
    "copyto": "use slice assignment a[:] = b", "fromiter": "use numpy.array(list(it))",
    "allclose": "ulab has no allclose", "isclose": "ulab has no isclose",
    "array_equal": "ulab has no array_equal", "count_nonzero": "ulab has no count_nonzero",
    "argwhere": "ulab has no argwhere", "pad": "ulab has no pad",
    "bool_": "use numpy.bool", "int_": "ulab has no int_", "float_": "use numpy.float",
}


def _make_modules() -> tuple[types.ModuleType, types.ModuleType]:
    unp = types.ModuleType("ulab.numpy", "ulab 6.x numpy stand-in (texelpad.ulab_standin)")
    ns: dict[str, Any] = {
        "ndarray": ndarray, "array": array, "arange": arange, "linspace": linspace,
        "zeros": zeros, "ones": ones, "empty": empty, "full": full,
        "concatenate": concatenate, "frombuffer": frombuffer,
        "sum": _sum, "mean": _mean, "std": _std,
        "min": _minmax("min", _np.min, False), "max": _minmax("max", _np.max, False),
        "argmin": _minmax("argmin", _np.argmin, True),
        "argmax": _minmax("argmax", _np.argmax, True),
        "clip": clip, "maximum": maximum, "minimum": minimum,
        "sort": sort, "argsort": argsort, "flip": flip,
        "e": float(_F32(math.e)), "pi": float(_F32(math.pi)),
        "inf": float("inf"), "nan": float("nan"),
        "bool": BOOL, "uint8": UINT8, "int8": INT8, "uint16": UINT16, "int16": INT16,
        "float": FLOAT,
    }
    for name, f in _UFUNCS.items():
        ns[name] = _ufunc(name, f)
    unp.__dict__.update(ns)

    def numpy_getattr(name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        if name in IN_ULAB_NOT_MODELLED:
            raise AttributeError("ulab.numpy.%s exists in ulab 6.x but the stand-in does not "
                                 "model it (add it to tests/support/ulab_standin.py)" % name)
        hint = ULAB_LACKS.get(name)
        if hint is not None:
            raise AttributeError("ulab 6.x has no numpy.%s: %s" % (name, hint))
        raise AttributeError("ulab 6.x has no numpy.%s" % name)

    unp.__getattr__ = numpy_getattr  # type: ignore[attr-defined]  # PEP 562

    top = types.ModuleType("ulab", "ulab stand-in (texelpad.ulab_standin)")
    top.__version__ = VERSION  # type: ignore[attr-defined]
    top.numpy = unp  # type: ignore[attr-defined]
    top.__path__ = []  # type: ignore[attr-defined]  # a package, so ulab.numpy imports

    def ulab_getattr(name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        if name in ("scipy", "utils", "user", "dtype"):
            raise AttributeError("ulab.%s exists in ulab but the stand-in does not model it"
                                 % name)
        raise AttributeError("ulab has no attribute %r" % name)

    top.__getattr__ = ulab_getattr  # type: ignore[attr-defined]
    return top, unp


ULAB, NUMPY = _make_modules()
_MODULE_NAMES = ("ulab", "ulab.numpy")
_saved: list[dict[str, Any]] = []


def is_installed() -> bool:
    return sys.modules.get("ulab") is ULAB and sys.modules.get("ulab.numpy") is NUMPY


def install() -> types.ModuleType:
    """Put the stand-in into sys.modules as ``ulab`` and ``ulab.numpy``;
    returns the numpy module. Nested installs are counted."""
    _saved.append({n: sys.modules.get(n) for n in _MODULE_NAMES})
    sys.modules["ulab"] = ULAB
    sys.modules["ulab.numpy"] = NUMPY
    return NUMPY


def uninstall() -> None:
    """Undo the last install(): restore what was in sys.modules before."""
    if not _saved:
        return
    prev = _saved.pop()
    for n in _MODULE_NAMES:
        if prev[n] is None:
            sys.modules.pop(n, None)
        else:
            sys.modules[n] = prev[n]


@contextmanager
def installed() -> Iterator[types.ModuleType]:
    """``with installed() as np:`` - the stand-in for the duration of the block."""
    np = install()
    try:
        yield np
    finally:
        uninstall()
