"""What the command line prints beyond the results: help text, plural words, the notes
at the end of a run."""
