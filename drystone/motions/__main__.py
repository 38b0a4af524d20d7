"""``python -m drystone.motions records`` | ``python -m drystone.motions spectrum FILE``: see motions.cli."""
import sys

from drystone.motions.cli import main

sys.exit(main())
