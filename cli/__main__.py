"""``python -m cli``: the diskfriction command line."""
from cli.main import main

raise SystemExit(main())
