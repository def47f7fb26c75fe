"""Running a scene's chunks: the one chunk loop, its backends (threads, dask), the journal, the output lock, progress,
the size check and the compile notice. The entry points that use them are sweep/api.py and sweep/cli.py."""
