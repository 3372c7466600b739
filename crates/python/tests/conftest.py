"""The tests import their helper modules (warp_capture.py) from this folder."""

import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
