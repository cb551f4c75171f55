"""Sim-to-real gap diagnosis (theory §6): where a model misfits measured data (localise), which
candidate effect explains it (attribute), how far the misfit shrinks on held-out files (report)."""
