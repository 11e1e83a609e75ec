"""CLI subcommands, discovered by module: each module defines ``ORDER`` and ``register(subparsers)``.

A command module must stay light at import time (``--help`` imports all of them): heavy packages
are imported inside the function that runs the command.
"""
