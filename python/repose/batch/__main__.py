"""`python3 -m repose.batch ARGS` (what `repose batch ARGS` runs)."""
import sys

from .runner import main

if __name__ == "__main__":  # Dask's spawned workers import this module again: run only in the parent
    sys.exit(main(sys.argv[1:]))
