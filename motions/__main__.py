"""``python -m motions records`` | ``python -m motions spectrum FILE``: see motions.cli."""
import sys

from motions.cli import main

sys.exit(main())
