"""The ulab 6.x stand-in (texelpad.ulab_standin) refuses what ulab lacks and
reproduces the ulab semantics that change results, each checked against
ulab's source (v923z/micropython-ulab, code/; named per test). If the stand-in
let these through, device code could pass on CPython and fail on a board."""
from __future__ import annotations

import sys
from array import array

import numpy
import pytest

import texel
from support import ulab_standin


@pytest.fixture
def np():
    """`ulab.numpy` for one test; sys.modules is restored afterwards."""
    before = {n: sys.modules.get(n) for n in ("ulab", "ulab.numpy")}
    mod = ulab_standin.install()
    try:
        yield mod
    finally:
        ulab_standin.uninstall()
        assert {n: sys.modules.get(n) for n in ("ulab", "ulab.numpy")} == before


def a(x):
    return ulab_standin.to_numpy(x)


# --- install / uninstall ---------------------------------------------------------

def test_import_works_only_while_installed():
    assert not ulab_standin.is_installed()
    with pytest.raises(ImportError):
        from ulab import numpy  # noqa: F401
    with ulab_standin.installed() as unp:
        from ulab import numpy
        import ulab
        assert numpy is unp and ulab.numpy is unp
        assert ulab.__version__ == "6.12.0-standin"
        assert texel.compat.ulab_numpy() is unp
        assert texel.compat.ulab_version() == "6.12.0-standin"
        assert "ulab" in texel.engines()
    assert "ulab" not in sys.modules and "ulab.numpy" not in sys.modules
    assert texel.compat.ulab_numpy() is None
    assert "ulab" not in texel.engines()


def test_nested_install_restores_in_order():
    ulab_standin.install()
    ulab_standin.install()
    ulab_standin.uninstall()
    assert ulab_standin.is_installed()          # the outer install still holds
    ulab_standin.uninstall()
    assert "ulab" not in sys.modules
    ulab_standin.uninstall()                    # extra uninstall: harmless
    assert "ulab" not in sys.modules


def test_stand_in_is_not_mistaken_for_numpy(np):
    # compat detects the real numpy by float64: the stand-in must not have it
    assert not hasattr(np, "float64")
    assert texel.compat.numpy_mod is numpy


# --- what ulab 6.x lacks (code/numpy/numpy.c, ulab_numpy_globals_table) ------------

@pytest.mark.parametrize("name", ["cumsum", "repeat", "searchsorted", "random",
                                  "int32", "uint32", "int64", "float64", "float32",
                                  "astype", "zeros_like", "isnan", "round", "abs"])
def test_refuses_names_ulab_lacks(np, name):
    assert not hasattr(np, name)
    with pytest.raises(AttributeError, match="ulab 6.x has no numpy.%s" % name):
        getattr(np, name)


def test_random_is_refused_with_the_reason(np):
    # ulab has numpy.random from 6.5.0, but SPEC §3: buggy, differs from numpy
    with pytest.raises(AttributeError, match="SPEC"):
        np.random


def test_names_in_ulab_but_not_modelled_say_so(np):
    with pytest.raises(AttributeError, match="exists in ulab 6.x"):
        np.fft
    with pytest.raises(AttributeError, match="exists in ulab 6.x"):
        np.interp


@pytest.mark.parametrize("method", ["astype", "sum", "cumsum", "repeat", "searchsorted",
                                    "fill", "min", "max", "mean", "ravel", "item", "ndim",
                                    "nbytes", "view"])
def test_arrays_have_no_numpy_only_methods(np, method):
    x = np.zeros(4)
    assert not hasattr(x, method)


def test_universal_function_out_keyword_refused(np):
    # out= exists only from 6.2.0 and only with ULAB_MATH_FUNCTIONS_OUT_KEYWORD
    x = np.zeros(3)
    with pytest.raises(TypeError, match="out"):
        np.sin(x, out=x)


def test_modulo_refused(np):
    # ndarray % exists from 6.9.0, broken until #749 (2026)
    x = np.arange(5, dtype=np.float)
    with pytest.raises(TypeError, match="6.9"):
        x % 2.0
    with pytest.raises(TypeError):
        x %= 2.0


def test_dtypes_are_ulab_typecodes(np):
    # class constants are ints: MP_ROM_INT(NDARRAY_UINT8) ... (code/ndarray.h)
    assert (np.bool, np.uint8, np.int8, np.uint16, np.int16, np.float) == \
        (ord("?"), ord("B"), ord("b"), ord("H"), ord("h"), ord("f"))
    with pytest.raises(TypeError):
        np.zeros(3, dtype=numpy.float32)        # a numpy dtype is not a ulab dtype


# --- semantics that change results ---------------------------------------------------

def test_float_is_float32(np):
    x = np.zeros(3) + 0.1                       # the scalar becomes mp_float_t
    assert x.dtype == np.float and a(x).dtype == numpy.float32
    assert x[0] == float(numpy.float32(0.1)) != 0.1
    assert isinstance(x[0], float)
    assert np.sin(1.0) == float(numpy.sin(numpy.float32(1.0)))


def test_arange_of_ints_is_int16(np):
    # create_arange: int arguments -> NDARRAY_INT16 unless |arg| > 32768
    assert np.arange(10).dtype == np.int16
    assert np.arange(2, 10, 3).tolist() == [2, 5, 8]
    assert np.arange(0, 40000, 10000).dtype == np.float
    assert np.arange(0.0, 3.0).dtype == np.float
    k = np.arange(1, 65, dtype=np.float)
    assert k.dtype == np.float and a(k).tolist() == list(range(1, 65))
    # int16 arithmetic wraps (same dtype in, same dtype out)
    assert (np.arange(30000, 30003) * 2).tolist() == [-5536, -5534, -5532]


def test_arange_accumulates_in_float32(np):
    # ARANGE_LOOP: value += step in mp_float_t; the last element is start+(n-1)*step
    x = a(np.arange(0.0, 1.0, 0.1))
    acc = numpy.float32(0.0)
    expect = []
    for _ in range(9):
        expect.append(acc)
        acc = numpy.float32(acc + numpy.float32(0.1))
    assert x[:9].tolist() == expect
    assert len(x) == 10


def test_float_to_uint16_rounds_half_away_and_wraps(np):
    # ndarray_copy_view_convert_type: (int32_t)round(f), stored with wrap
    f = np.array([0.4, 0.5, 1.5, 2.5, 65534.5, 65535.4, 65535.5, -0.4, -0.6])
    q = np.array(f, dtype=np.uint16)
    assert q.dtype == np.uint16
    assert q.tolist() == [0, 1, 2, 3, 65535, 65535, 0, 0, 65535]
    # slice assignment converts the same way (ndarray_assign_view)
    out = np.zeros(9, dtype=np.uint16)
    out[0:9] = f
    assert out.tolist() == q.tolist()


def test_list_of_floats_into_int_dtype_is_a_type_error(np):
    # mp_binary_set_val_array -> mp_obj_get_int(float): TypeError on MicroPython
    with pytest.raises(TypeError):
        np.array([1.5, 2.0], dtype=np.uint16)
    assert np.array([1, 70000], dtype=np.uint16).tolist() == [1, 70000 - 65536]


def test_upcasting_follows_ulab_not_numpy(np):
    u8 = np.array([1, 2], dtype=np.uint8)
    i8 = np.array([1, 2], dtype=np.int8)
    u16 = np.array([1, 2], dtype=np.uint16)
    i16 = np.array([1, 2], dtype=np.int16)
    assert (u8 + i8).dtype == np.int16
    assert (u8 + u16).dtype == np.uint16
    assert (u16 + i16).dtype == np.float          # numpy: int32
    assert (i8 + u16).dtype == np.int16           # ndarray_binary_add (docs say uint16)
    assert (u8 * 2).dtype == np.uint8             # 2 -> uint8 scalar array
    assert (u8 * 300).dtype == np.uint16
    assert (u8 + 100000).dtype == np.float        # beyond 16 bits -> float
    assert (u8 + 255).tolist() == [0, 1]          # same dtype wraps
    # reversed operands: the scalar's dtype ignores the array's (other_type 0)
    assert (i8 + 5).dtype == np.int8 and (5 + i8).dtype == np.int16
    assert (i16 / 2).dtype == np.float and (u8 ** 2).dtype == np.float


def test_inplace_keeps_dtype_and_refuses_float_into_int(np):
    x = np.zeros(4, dtype=np.int16)
    with pytest.raises(TypeError):
        x += 1.5
    with pytest.raises(TypeError):
        x /= 2
    x += 3
    assert x.dtype == np.int16 and x.tolist() == [3, 3, 3, 3]


def test_slices_are_views_and_inplace_writes_through(np):
    x = np.zeros(8)
    v = x[2:5]
    v += 1.0
    v *= 3.0
    assert x.tolist() == [0, 0, 3, 3, 3, 0, 0, 0]
    y = x[2:5] * 2.0                              # binary ops make a new array
    y += 1.0
    assert x[2] == 3.0


def test_truthiness_is_length_not_elementwise(np):
    # no BOOL unary op on ndarray: MicroPython falls back to len()
    assert bool(np.zeros(3) > 1.0) is True
    assert bool(np.zeros(0)) is False


def test_frombuffer_shares_memory(np):
    buf = array("H", bytes(8))
    v = np.frombuffer(buf, dtype=np.uint16)
    v[1:3] = np.array([1.6, 2.4])
    assert buf.tolist() == [0, 2, 2, 0]


def test_sum_of_ints_is_a_rounded_int(np):
    # numerical_sum_mean_std_ndarray: running float mean, then round(M * len)
    assert np.sum(np.array([1, 2, 3], dtype=np.uint8)) == 6
    assert isinstance(np.sum(np.array([1, 2, 3], dtype=np.uint8)), int)
    assert np.mean(np.array([1.0, 2.0])) == 1.5


def test_indexing(np):
    x = np.array([[1, 2], [3, 4]], dtype=np.int16)
    assert x.shape == (2, 2) and x[1, 0] == 3 and isinstance(x[1, 0], int)
    with pytest.raises(IndexError):
        x[[0, 1]]                                 # lists are not ulab indices
    with pytest.raises(TypeError, match="too many dimensions"):
        np.zeros((2, 2, 2))                        # ULAB_MAX_DIMS = 2
