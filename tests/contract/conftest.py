# SPDX-License-Identifier: Apache-2.0
"""Settings of the contract suite (README.md in this folder).

Two Hypothesis profiles, chosen with FLT_CONTRACT_PROFILE:
  ci       (default) derandomized: the same examples on every run, so a red
           run is reproducible and a green one stays green; no example
           database; a bounded number of examples per test (about a minute
           and a half for the whole suite on the development machine).
  explore  random seeds and ten times the examples, for a longer hunt;
           `--hypothesis-seed=N` pins one.
FLT_CONTRACT_SCALE multiplies the examples of either profile (e.g. 0.2 for a
quick look, 5 for a long run).

The suite runs under an address-space limit of its own
(FLT_CONTRACT_MEMORY_GB, 4 GiB; 0 for none; Linux and other POSIX systems):
an example that makes memory grow fails inside the suite with MemoryError or
flatline.OutOfMemoryError, and Hypothesis prints it, where without a limit
the kernel's out-of-memory killer would end the process without a word. The
suite needs about 0.4 GB (README.md).
"""

import os

from hypothesis import HealthCheck, settings

_SCALE = float(os.environ.get("FLT_CONTRACT_SCALE", "1"))
_COMMON = dict(
    deadline=None,  # the suite bounds the time per row itself (contract.call)
    database=None,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                           HealthCheck.filter_too_much],
)
settings.register_profile("ci", derandomize=True, max_examples=max(1, int(100 * _SCALE)),
                          **_COMMON)
settings.register_profile("explore", derandomize=False,
                          max_examples=max(1, int(1000 * _SCALE)), **_COMMON)
settings.load_profile(os.environ.get("FLT_CONTRACT_PROFILE", "ci"))


def _limit_address_space() -> None:
    gigabytes = float(os.environ.get("FLT_CONTRACT_MEMORY_GB", "4"))
    if gigabytes <= 0:
        return
    try:
        import resource
    except ImportError:  # Windows: no rlimits
        return
    limit = int(gigabytes * (1 << 30))
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    if soft == resource.RLIM_INFINITY or soft > limit:
        resource.setrlimit(resource.RLIMIT_AS, (limit, hard))


_limit_address_space()


def examples(count: int) -> int:
    """A test's own example count (relative to the profile's 100), scaled."""
    base = settings.default.max_examples / 100.0
    return max(1, int(count * base))
