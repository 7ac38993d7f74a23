"""test_abi.py runs first; when one of its tests fails, the ctypes mirrors
differ from the C structures and every other test is skipped (saying why):
a call through a wrong mirror may crash the interpreter before pytest
reports the difference."""
import pytest

ABI_TESTS = "test_abi.py"


def pytest_collection_modifyitems(session, config, items):
    items.sort(key=lambda item: item.path.name != ABI_TESTS)  # stable: each file keeps its order


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    if outcome.get_result().failed and item.path.name == ABI_TESTS:
        item.config.stash.setdefault(_ABI_FAILED, []).append(item.name)


def pytest_runtest_setup(item):
    failed = item.config.stash.get(_ABI_FAILED, [])
    if failed and item.path.name != ABI_TESTS:
        pytest.skip(f"not run: the ctypes mirrors differ from the C structures ({', '.join(failed)} failed); "
                    "calling the library through them could crash")


_ABI_FAILED = pytest.StashKey[list]()


# the package beside the tests, also when pytest runs from the repository's root
import os  # noqa: E402
import sys  # noqa: E402

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), "..")))
