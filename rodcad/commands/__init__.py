"""Subcommands of the ``rodcad`` CLI, one module each."""
