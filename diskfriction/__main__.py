"""``python -m diskfriction``: the diskfriction command line."""
from diskfriction.cli.main import main

raise SystemExit(main())
