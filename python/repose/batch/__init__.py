"""The batch runner behind `repose batch`: many subjects x many poses and BVH frames on Dask
distributed, resumable, with a record of what ran (see docs/batch.md)."""
