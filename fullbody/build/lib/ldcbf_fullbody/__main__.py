"""``python3 -m ldcbf_fullbody``: see ``cli.py``."""

import sys

from .cli import main

sys.exit(main())
