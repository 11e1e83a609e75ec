"""CLI subcommands: each module defines ``register(subparsers)``; ``cli.main.COMMANDS`` lists them.

A command module must stay light at import time (``--help`` imports all of them): heavy packages,
NumPy included, are imported inside the function that runs the command.
"""
