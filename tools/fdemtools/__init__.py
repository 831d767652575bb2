"""fdem post-processing tools: EEEP ductility, ductility regression, hysteresis, plots, crack maps,
parameter studies and batches of fdem runs. Command line: tools/fdem-tools (see tools/README.md)."""
__version__ = "0.1.0"
