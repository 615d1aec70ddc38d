"""The ``rodcad`` command line.

Every subcommand lives in its own module exposing ``register(subparsers)``; the
module's handler receives the parsed arguments and returns an exit code:
0 done, 1 the job ran but failed, 2 bad input (problems printed as
``FILE:LINE:COL: key.path: message`` on stderr, no traceback).
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
from collections.abc import Sequence

from rodcad import __version__
from rodcad.errors import DesignLimit, InputError
from rodcad.outdir import OutputFolderError

#: Modules that register subcommands, in the order ``--help`` lists them.
COMMAND_MODULES = (
    "rodcad.commands.build",
    "rodcad.commands.simulate",
    "rodcad.commands.check",
    "rodcad.commands.catalog",
    "rodcad.commands.calibrate",
    "rodcad.commands.schema",
    "rodcad.commands.demo",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rodcad",
        description="Design and 3D-print hanging rod chains that settle into a chosen shape.",
    )
    parser.add_argument("--version", action="version", version=f"rodcad {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if _builds_solids(argv):  # the workers' process imports the CAD kernel while this one imports the rest
        from rodcad.parallel import start_workers

        start_workers()
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "handler", None):
        parser.print_help()
        return 2
    signal.signal(signal.SIGTERM, _terminate)  # clean up staging folders on `kill` too
    try:
        return int(args.handler(args))
    except InputError as err:
        for problem in err.problems:
            print(problem, file=sys.stderr)
        return 2
    except OutputFolderError as err:
        print(f"rodcad: {err}", file=sys.stderr)
        return 2
    except DesignLimit as err:
        print(f"rodcad: {err}; outputs left as they were", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("rodcad: interrupted; outputs left as they were", file=sys.stderr)
        return 1
    except (RecursionError, MemoryError) as err:
        print(f"rodcad: the input is too large or too deeply nested to handle ({type(err).__name__}); "
              "outputs left as they were", file=sys.stderr)
        return 2
    except Exception as err:  # a bug: say so in one line, keep the traceback for RODCAD_DEBUG=1
        if os.environ.get("RODCAD_DEBUG"):
            raise
        print(f"rodcad: internal error ({type(err).__name__}: {err}); outputs left as they were. Please report it "
              "with the design file; RODCAD_DEBUG=1 shows the traceback", file=sys.stderr)
        return 1


def _builds_solids(argv: Sequence[str]) -> bool:
    """Whether the command line is a ``rodcad build`` that may build solids in worker
    processes (no ``--no-cad``, no ``--jobs 1``, no ``--help``; no ``--jobs`` where the run may
    use one CPU: :func:`rodcad.parallel.default_jobs`)."""
    if not argv or argv[0] != "build" or any(a in ("--no-cad", "-h", "--help") for a in argv):
        return False
    for a, b in zip(argv, argv[1:] + [""]):
        if (a == "--jobs" and b == "1") or a == "--jobs=1":
            return False
        if a == "--jobs" or a.startswith("--jobs="):
            return True
    from rodcad.parallel import default_jobs

    try:
        return default_jobs() > 1
    except InputError:  # said by the build itself
        return False


def _terminate(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def console_main() -> None:  # pragma: no cover - the installed command (tests run it as a subprocess)
    """The ``rodcad`` command: :func:`main`, then the process ends without unloading its modules.

    Everything is written by then; the exit handlers (worker processes, temporary folders,
    logging) run and the output is flushed first. Unloading the CAD kernel's modules one by one
    took about half a second after every build with solids, and nothing needs it."""
    code = main()
    import atexit

    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe (``rodcad ... | head``): nothing more to say
            pass
    os._exit(code)


if __name__ == "__main__":  # pragma: no cover - ``python -m rodcad.cli`` (profilers run after main returns)
    sys.exit(main())
