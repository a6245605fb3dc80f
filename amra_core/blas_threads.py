"""One BLAS thread per worker process.

NumPy and SciPy each load an OpenBLAS that starts one thread per core for a matrix product or an
eigen-decomposition. A map worker's matrices are small (tens of rows: monodromy, Jacobians), and a
pool already runs one worker per core: with every worker's OpenBLAS spinning threads on every core,
the workers take each other's cycles. Measured on the 2-core machine (``python scripts/bench_map.py
--only fem-coupled_mu0.1 --pool warm``): 72.5 s and 147 s of CPU with OpenBLAS's default threads,
47.1 s and 94 s of CPU with one thread each (the columns alone sum to 86 s of CPU either way).

:func:`use_one_blas_thread` is the initializer of every process pool's workers (a library call,
:mod:`threadpoolctl`, not environment variables: those only act before NumPy is first imported)."""
from __future__ import annotations


def use_one_blas_thread() -> None:
    """Limit every BLAS library loaded by NumPy and SciPy in this process to one thread."""
    import numpy  # noqa: F401 - loaded first, so that the limit reaches its BLAS
    import scipy.linalg  # noqa: F401 - SciPy's wheels carry their own OpenBLAS
    from threadpoolctl import threadpool_limits
    threadpool_limits(limits=1, user_api="blas")
