"""Run the command line: ``python -m regopack``."""

from regopack.cli.commands import main

raise SystemExit(main())
