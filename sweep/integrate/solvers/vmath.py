"""Branch-free exp that LLVM can vectorise, in float64 and float32.

numba's ``math.exp`` calls libm (~8 ns, scalar: a loop over lanes containing it is not vectorised, and numba
has no SVML). These versions are straight-line code: Cody-Waite range reduction x = n ln2 + r, |r| <= ln2/2,
a Taylor polynomial in r (degree 13 / 7: truncation below 2e-16 / 5e-9 relative, under one ulp), and 2^n
built from its bits. The polynomial is 1 + r (1 + r q(r)) with q in Estrin's scheme (powers r^2, r^4, r^8):
about 6 dependent operations instead of Horner's 13, which matters because a stage of the lane kernels is
latency-bound (3.55 -> 2.84 ns per stage evaluation of RK4 in lanes), and the O(1) terms are added last so
that the result stays within one ulp (tests/integrate/test_vmath.py). A loop over lanes calling them compiles to
AVX2/AVX-512 code (12x libm per value, measured on a loop of 1e6 values; benchmarks/work_precision.py measures
the kernels).

Arguments are clamped to the normal range first (exp(-708) ~ 3e-308 stands for every smaller value, exp(708)
for larger): callers that must not see overflow test their exponent themselves (models/stop.py: EXP_MAX).
The functions require ``error_model="numpy"`` in the caller (no zero-division branches) to vectorise.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from ...jitcache import pin_module
from .fastmath import FAST

__all__ = ["EXP_MAX", "exp_f32", "exp_f64", "exp_f64_coarse", "log2_approx"]

EXP_MAX = 700.0
"""Largest exponent a model passes to exp (exp(709.8) overflows float64): beyond it a point is flagged nonfinite
(or, where a rate is clamped, the clamp keeps it finite)."""


@intrinsic
def _bits_as_float(typingctx, bits):
    """Reinterpret an int64 (int32) as a float64 (float32): the 2^n of the range reduction."""
    if bits == types.int64:
        sig, target = types.float64(types.int64), ir.DoubleType()
    elif bits == types.int32:
        sig, target = types.float32(types.int32), ir.FloatType()
    else:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], target)

    return sig, codegen


@intrinsic
def _float_as_bits(typingctx, x):
    """Reinterpret a float64 (float32) as an int64 (int32)."""
    if x == types.float64:
        sig, target = types.int64(types.float64), ir.IntType(64)
    elif x == types.float32:
        sig, target = types.int32(types.float32), ir.IntType(32)
    else:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], target)

    return sig, codegen


# float64: adding 1.5 * 2^52 rounds x log2(e) to the integer n, which then sits in the low mantissa bits
_LOG2E = 1.4426950408889634
_LN2_HI = 0.6931471803691238  # ln 2 with its low 32 mantissa bits zero: n * _LN2_HI is exact
_LN2_LO = 1.9082149292705877e-10
_ROUND = 6755399441055744.0
_ROUND_BITS = 0x4338000000000000
_P64 = tuple(1.0 / math.factorial(i) for i in range(14))

# float32: the same with 1.5 * 2^23; every constant is float32 so that no operation promotes to float64
_F = np.float32
_LOG2E_32, _LN2_HI_32, _LN2_LO_32 = _F(1.442695), _F(0.693359375), _F(-2.12194440e-4)
_ROUND_32, _ROUND_BITS_32, _BIAS_32 = _F(12582912.0), np.int32(0x4B400000), np.int32(127)
_SHIFT_32 = np.int32(23)
_LO_32, _HI_32 = _F(-87.0), _F(88.0)
_P32 = tuple(_F(1.0 / math.factorial(i)) for i in range(8))


@njit(inline="always", fastmath={"nsz": True, "contract": True}, error_model="numpy", cache=True)
def _reduce_f64(x):
    """(t, r) of float64 x clamped to [-708, 708]: x = n ln2 + r, |r| <= ln2/2, with n held in t's low mantissa bits
    (:func:`_two_to_the_f64` builds 2^n from them)."""
    x = min(max(x, -708.0), 708.0)
    t = x * _LOG2E + _ROUND
    n = t - _ROUND
    return t, (x - n * _LN2_HI) - n * _LN2_LO


@njit(inline="always", fastmath={"nsz": True, "contract": True}, error_model="numpy", cache=True)
def _two_to_the_f64(t):
    """2^n from the t of :func:`_reduce_f64`."""
    return _bits_as_float((_float_as_bits(t) - _ROUND_BITS + 1023) << 52)


@njit(inline="always", fastmath={"nsz": True, "contract": True}, error_model="numpy", cache=True)
def exp_f64(x: float) -> float:
    """exp(x) for float64, relative error <= 2.3e-16 for -708 <= x <= 708 (clamped outside)."""
    t, r = _reduce_f64(x)
    c = _P64  # written out: a loop over the tuple would index it at run time
    r2 = r * r
    r4 = r2 * r2
    q = ((c[2] + c[3] * r) + (c[4] + c[5] * r) * r2) + ((c[6] + c[7] * r) + (c[8] + c[9] * r) * r2) * r4
    q = q + ((c[10] + c[11] * r) + (c[12] + c[13] * r) * r2) * (r4 * r4)
    p = c[0] + r * (c[1] + r * q)
    return p * _two_to_the_f64(t)


@njit(inline="always", fastmath={"nsz": True, "contract": True}, error_model="numpy", cache=True)
def _taylor7(r, c):
    """sum_{i <= 7} c_i r^i (c_i = 1/i!, in r's float type) as 1 + r (1 + r q(r)), q in Estrin's scheme: the
    polynomial of exp_f32 and exp_f64_coarse."""
    r2 = r * r
    q = (c[2] + c[3] * r) + (c[4] + c[5] * r) * r2 + (c[6] + c[7] * r) * (r2 * r2)
    return c[0] + r * (c[1] + r * q)


@njit(inline="always", fastmath={"nsz": True, "contract": True}, error_model="numpy", cache=True)
def exp_f64_coarse(x: float) -> float:
    """exp(x) for float64 to a relative error <= 1e-8 for -708 <= x <= 708 (clamped outside): the range reduction
    of exp_f64 with the Taylor polynomial of degree 7 (that of exp_f32), about half the operations; for terms that
    need far less accuracy than a float64 carries (the source of the first-order inertial correction,
    sweep/integrate/models/stop_inertial.py, which decides the model to model_tol)."""
    t, r = _reduce_f64(x)
    return _taylor7(r, _P64) * _two_to_the_f64(t)


@njit(inline="always", fastmath={"nsz": True, "contract": True}, error_model="numpy", cache=True)
def exp_f32(x):
    """exp(x) for float32, relative error <= 2 ulp for -87 <= x <= 88 (clamped outside)."""
    x = min(max(x, _LO_32), _HI_32)
    t = x * _LOG2E_32 + _ROUND_32
    n = t - _ROUND_32
    r = (x - n * _LN2_HI_32) - n * _LN2_LO_32
    p = _taylor7(r, _P32)
    # numba widens int32 arithmetic to int64: narrow back before reinterpreting the bits as float32
    return p * _bits_as_float(np.int32((_float_as_bits(t) - _ROUND_BITS_32 + _BIAS_32) << _SHIFT_32))


_MANTISSA = 0x000FFFFFFFFFFFFF
_ONE_BITS = 0x3FF0000000000000
_MAGIC_BITS = 0x4330000000000000  # 2^52: an integer OR-ed into its mantissa is read back exactly by subtracting it
_MAGIC = 4503599627370496.0


@njit(inline="always", fastmath=FAST, error_model="numpy", cache=True)
def log2_approx(x):
    """log2(x) for a positive normal float64 to about 0.005 (a quadratic in the mantissa), in operations LLVM
    vectorises (bit masks and float arithmetic; int64 -> float64 conversion, which AVX2 lacks, is avoided by
    reading the exponent bits as the mantissa of 2^52): the step controllers' logarithm (the adaptive lanes, the
    driven drivers; a step factor needs no more)."""
    bits = _float_as_bits(x)
    exponent = _bits_as_float((bits >> 52) | _MAGIC_BITS) - _MAGIC - 1023.0
    m = _bits_as_float((bits & _MANTISSA) | _ONE_BITS)  # in [1, 2)
    return exponent + ((-0.34484843 * m + 2.02466578) * m - 1.67487759)


pin_module(__name__)
