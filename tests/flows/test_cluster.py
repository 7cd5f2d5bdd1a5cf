"""``flows.cluster.check_workers``: the one rule for worker counts, CLI and Python alike."""

import numpy as np
import pytest

from flows.cluster import ClusterError, check_workers, dask_client


@pytest.mark.parametrize("value", [1, "3", np.int64(2)])
def test_whole_numbers_from_one_up_are_worker_counts(value):
    assert check_workers(value) == int(value)


@pytest.mark.parametrize("value", [0, -1, "0", "two", "1.5", 2.0, True, None])
def test_anything_else_is_refused_naming_the_value(value):
    with pytest.raises(ClusterError, match=r"need a whole number >= 1") as caught:
        check_workers(value)
    assert str(caught.value).startswith(repr(value))


def test_the_python_name_prefixes_the_message():
    with pytest.raises(ClusterError, match=r"^workers 0: need a whole number >= 1$"):
        check_workers(0, name="workers")


def test_a_local_cluster_is_refused_before_it_starts():
    with pytest.raises(ClusterError, match=r"^workers -2: "), dask_client(workers=-2):
        pytest.fail("a cluster started")
