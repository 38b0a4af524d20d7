"""python -m drystone.studies.tilt [--seeds DIR] [--rate DIR] [--sensitivity DIR] [--extruded DIR] [--out DIR]"""
import sys

from drystone.studies.tilt.study import main

sys.exit(main())
