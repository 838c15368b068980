import pytest

import thinburn


def test_thread_count_round_trips():
    old = thinburn.get_threads()
    try:
        assert thinburn.set_threads(1) == 1
        assert thinburn.get_threads() == 1
        if thinburn.has_openmp():
            assert thinburn.set_threads(2) == 2
            assert thinburn.get_threads() == 2
    finally:
        thinburn.set_threads(old)


@pytest.mark.parametrize("bad, exc", [(0, ValueError), (-3, ValueError), (2.5, TypeError), (True, TypeError)])
def test_bad_thread_count_names_the_argument(bad, exc):
    with pytest.raises(exc, match="threads"):
        thinburn.set_threads(bad)
