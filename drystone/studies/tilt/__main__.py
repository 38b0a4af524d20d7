"""python -m drystone.studies.tilt [--run GROUP ...] [--workers N] [--dask ADDRESS] [--seeds DIR] [--rate DIR]
[--sensitivity DIR] [--extruded DIR] [--out DIR]: run the groups' tilt analyses (seeds, extruded, rate,
sensitivity), then the report of results/tilt/."""
import sys

from drystone.studies.tilt.study import main

sys.exit(main())
