"""rodcad: computational design and fabrication of hanging rod chains.

The numerics live in the sibling package :mod:`optimize` (numpy/scipy only);
this package owns YAML input, rod catalogs, CAD, export, reports and the CLI.
"""

__version__ = "0.1.0"
