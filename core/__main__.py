"""Run the command line: ``python -m regopack``."""

from regopack.cli import main

raise SystemExit(main())
