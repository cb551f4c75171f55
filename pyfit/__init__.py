"""pyfit: Modelica -> FMU build, FMU simulation and analysis for hysteretic dampers (SI units)."""

__version__ = "0.2.0"
