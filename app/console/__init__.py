"""What the command line shares between verbs: common options (options.py) and printing figures (output.py)."""
