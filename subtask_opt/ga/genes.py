"""Element loops over gene rows (int64 arrays), shared by the loop and the operators.

Element loops rather than slice assignment: a slice assignment compiles numba's shape
check and its error formatting into every kernel that reaches it, which made the cold
compile of the GA loop measurably slower.
"""

from __future__ import annotations

from numba import njit


@njit(cache=True, inline="always")
def copy_run(dst, dst_at, src, src_at, count):
    """``dst[dst_at : dst_at + count] = src[src_at : src_at + count]`` (no overlap)."""
    for k in range(count):
        dst[dst_at + k] = src[src_at + k]


@njit(cache=True, inline="always")
def reverse_run(a, start, stop):
    """Reverse ``a[start:stop]`` in place."""
    i, j = start, stop - 1
    while i < j:
        a[i], a[j] = a[j], a[i]
        i += 1
        j -= 1
