"""The README opens with the two commands, and CI runs its test command verbatim."""

from pathlib import Path


def test_ci_runs_the_readme_test_command() -> None:
    lines = Path("README.md").read_text().splitlines()
    start = lines.index("```bash") + 1
    main_job, tests = (line.split("#")[0].strip() for line in lines[start : start + 2])
    assert main_job.startswith("pip install -e")
    ci = Path(".ci/run").read_text().splitlines()
    assert ci[-1].strip() == tests
