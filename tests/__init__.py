"""The test suite (``tests/README.md``): a package, so its modules import each other as
``tests.<folder>.<module>`` and the helpers as ``tests.support.<module>``."""

import pytest

# before conftest.py imports any helper: their asserts then say what they compared
pytest.register_assert_rewrite("tests.support")
