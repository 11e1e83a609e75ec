"""``python -m drive_envelope``: the drive-envelope CLI."""

from drive_envelope._src.cli.main import main

raise SystemExit(main())
