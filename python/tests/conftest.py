import os
import sys

# The helpers module beside the tests (the installed package `plateau` is what is tested).
sys.path.insert(0, os.path.dirname(__file__))
