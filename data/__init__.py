"""Shipped configurations (presets) and reference data; installed as ``rodjit.data``."""
