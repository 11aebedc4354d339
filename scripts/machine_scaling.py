"""What this machine gives a second thread: a kernel bound by arithmetic and one bound by
memory, each at 1, 2, ... threads (Numba's), the fastest of ``--rounds``. A stage of the
match scales between the two, by its share of memory traffic: where the memory's rate does
not grow with the threads, neither does that share of the stage.

    python scripts/machine_scaling.py [--threads 1,2] [--rounds 3] [--megabytes 640]
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np
from numba import njit, prange


@njit(parallel=True)
def _arithmetic(steps, out):
    """A chain of multiply-adds per element: no memory traffic to speak of."""
    for i in prange(out.size):
        x = np.float32(i)
        total = np.float32(0.0)
        for _ in range(steps):
            x = x * np.float32(1.0000001) + np.float32(0.5)
            total += x
        out[i] = total


@njit(parallel=True)
def _streaming(a, b):
    """b = 1.5 a + 1 over arrays far larger than the caches: one read and one write a cell."""
    for i in prange(a.shape[0]):
        for j in range(a.shape[1]):
            b[i, j] = a[i, j] * np.float32(1.5) + np.float32(1.0)


def fastest(call, rounds: int) -> float:
    best = float("inf")
    for _ in range(rounds):
        start = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threads", default="1,2")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--megabytes", type=int, default=640)
    args = parser.parse_args()
    threads = [int(t) for t in args.threads.split(",")]
    rows = max(1, args.megabytes * 2 ** 20 // 4 // 40000)
    a = np.ones((rows, 40000), np.float32)
    b = np.empty_like(a)
    out = np.zeros(16 * max(threads), np.float32)
    _arithmetic(10, out)
    _streaming(a, b)
    steps = 4_000_000
    seconds = {}
    for count in threads:
        numba.set_num_threads(count)
        seconds[count] = (fastest(lambda: _arithmetic(steps, out), args.rounds),
                          fastest(lambda: _streaming(a, b), args.rounds))
    one = seconds[threads[0]]
    moved = 2 * a.nbytes / 1e9
    print("threads   arithmetic s (x)      streaming s (x)   memory GB/s")
    for count, (arith, stream) in seconds.items():
        print(f"{count:7d}   {arith:8.3f} ({one[0] / arith:4.2f})   {stream:8.3f} "
              f"({one[1] / stream:4.2f})   {moved / stream:8.1f}")


if __name__ == "__main__":
    main()
