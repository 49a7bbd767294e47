"""Files: HDF5 results and their schema (one writer, resumable), reading measured height
maps, and PNG summaries of a run."""
