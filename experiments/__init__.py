"""Studies (docs/problems.md, 'Experiments'): thin ``main(config)`` scripts that write tidy data files; plots
read only those files.

Run one with ``catenary experiment NAME [--full]`` or ``python -m experiments.NAME``; re-plot everything from
the data with ``catenary report``.
"""
