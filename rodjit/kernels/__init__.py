"""Compiled building blocks: forces, energies, banded solves (no time stepping here)."""
