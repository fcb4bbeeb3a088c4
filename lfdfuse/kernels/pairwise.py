"""numpy's pairwise summation, written out for compiled loops that must give numpy's bits.

``np.add.reduce`` of a contiguous float64 array sums blocks of at most :data:`PW_BLOCK` elements
with eight accumulators and splits longer runs in two (at a multiple of eight), adding the
halves. :func:`pairwise_sum` does the same over a scratch buffer for a loop compiled by
:func:`lfdfuse.kernels.jit.kernel` (named in its ``calls``); :func:`pairwise_sum_reference` is the same
model in plain Python, held to numpy by the tests.
"""

from __future__ import annotations

import numpy as np

#: blocks of at most this many elements are summed with eight accumulators
PW_BLOCK = 128
#: the depth of the split tree :func:`pairwise_sum`'s stacks hold (2 × log₂ of any array)
STACK = 64


def pairwise_sum(
    buf: np.ndarray,
    length: int,
    stack_lo: np.ndarray,
    stack_n: np.ndarray,
    stack_st: np.ndarray,
    vals: np.ndarray,
) -> float:
    """numpy's pairwise sum of ``buf[:length]``, post-order over its split tree, with the
    caller's scratch stacks (``int64 (STACK,)`` ×3, ``float64 (STACK,)``): no allocation per sum."""
    vp = 0
    stack_lo[0] = 0
    stack_n[0] = length
    stack_st[0] = 0
    sp = 1
    while sp > 0:
        lo = stack_lo[sp - 1]
        cnt = stack_n[sp - 1]
        if cnt <= PW_BLOCK:
            sp -= 1
            if cnt < 8:
                res = 0.0
                for k in range(cnt):
                    res += buf[lo + k]
            else:
                a0 = buf[lo]
                a1 = buf[lo + 1]
                a2 = buf[lo + 2]
                a3 = buf[lo + 3]
                a4 = buf[lo + 4]
                a5 = buf[lo + 5]
                a6 = buf[lo + 6]
                a7 = buf[lo + 7]
                k = 8
                stop = cnt - cnt % 8
                while k < stop:
                    a0 += buf[lo + k]
                    a1 += buf[lo + k + 1]
                    a2 += buf[lo + k + 2]
                    a3 += buf[lo + k + 3]
                    a4 += buf[lo + k + 4]
                    a5 += buf[lo + k + 5]
                    a6 += buf[lo + k + 6]
                    a7 += buf[lo + k + 7]
                    k += 8
                res = ((a0 + a1) + (a2 + a3)) + ((a4 + a5) + (a6 + a7))
                while k < cnt:
                    res += buf[lo + k]
                    k += 1
            vals[vp] = res
            vp += 1
        elif stack_st[sp - 1] == 0:
            stack_st[sp - 1] = 1
            half = cnt // 2
            half -= half % 8
            stack_lo[sp] = lo + half
            stack_n[sp] = cnt - half
            stack_st[sp] = 0
            stack_lo[sp + 1] = lo
            stack_n[sp + 1] = half
            stack_st[sp + 1] = 0
            sp += 2
        else:
            sp -= 1
            vals[vp - 2] = vals[vp - 2] + vals[vp - 1]
            vp -= 1
    return 0.0 + float(vals[0])  # numpy starts from the identity: -0.0 sums to +0.0


def pairwise_sum_reference(x: np.ndarray) -> float:
    """numpy's pairwise sum of a contiguous 1-D float64 array, recursively in Python (the model
    :func:`pairwise_sum` follows; the tests hold both to ``np.add.reduce``)."""

    def part(lo: int, n: int) -> float:
        if n < 8:
            res = 0.0
            for i in range(n):
                res += float(x[lo + i])
            return res
        if n <= PW_BLOCK:
            acc = [float(x[lo + j]) for j in range(8)]
            i = 8
            while i < n - n % 8:
                for j in range(8):
                    acc[j] += float(x[lo + i + j])
                i += 8
            res = ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]))
            while i < n:
                res += float(x[lo + i])
                i += 1
            return res
        n2 = n // 2
        n2 -= n2 % 8
        return part(lo, n2) + part(lo + n2, n - n2)

    return 0.0 + part(0, len(x))
