"""Benchmark entry point (``make bench``): ``python tests/bench/run.py [section ...]``.

Prints the environment once, then each section's Markdown report to stdout, and writes
``results/bench/<section>.md`` and ``.json``. A section is a module under ``tests/bench``
with ``NAME`` and ``run()`` returning a ``common.Section`` (or just its Markdown). Add new
ones (tracking simulation, DC iteration, targeting, sweeps, the command itself) to
``SECTIONS``. Progress goes to stderr.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

if __package__ in (None, ""):  # run as a script: make the repository importable
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from tests.bench import (  # noqa: E402
    cli,
    common,
    guidance,
    kernels,
    od,
    od_peer,
    processor,
    propagation,
    sweeps,
    targeting,
    tracking,
)

SECTIONS = {module.NAME: module
            for module in (propagation, tracking, od, od_peer, targeting, sweeps, processor,
                           guidance, kernels, cli)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sections", nargs="*", metavar="section",
                        help=f"sections to run, among {', '.join(SECTIONS)} (default: all)")
    args = parser.parse_args(argv)
    unknown = [name for name in args.sections if name not in SECTIONS]
    if unknown:
        parser.error(f"unknown section(s) {', '.join(unknown)}; known: {', '.join(SECTIONS)}")
    env = common.environment()
    print(common.environment_markdown(env), flush=True)
    for name in args.sections or list(SECTIONS):
        section = SECTIONS[name].run()
        if isinstance(section, str):  # a section may return only its Markdown
            section = common.Section(name, section)
        md, js = section.write(env)
        print("\n" + section.markdown, flush=True)
        print(f"\nWritten: {md.relative_to(common.REPO_ROOT)}, "
              f"{js.relative_to(common.REPO_ROOT)}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
