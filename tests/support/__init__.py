"""What the tests share that is not a fixture (the fixtures are in ``tests/conftest.py``).

``paths`` (the checkout, the configs the tests fly, ``tests/data``), ``commands``
(the ``gcs`` command line run in a subprocess or in this process),
``scheduling`` (how the suite is spread over pytest-xdist's workers), ``ports``,
``links`` (a Link on UDP and a socket playing its vehicle), ``worlds`` (the
simulator's world with one vehicle), ``flights`` (a team flown against the real
simulator), ``scripted_autopilot``, ``double_integrator``, ``logfiles``,
``fuzzing`` and ``colours``.

Their asserts are rewritten by pytest as a test module's are (``tests/__init__.py``),
so a helper's failing check says what it compared.
"""
