import sys
from pathlib import Path

# brute_force.py (the independent NumPy reference) sits beside the tests.
sys.path.insert(0, str(Path(__file__).parent))
