"""The ``Sink`` protocol: what receives the rows a run drains from its output buffers."""
from __future__ import annotations

__all__ = ["Sink"]


class Sink:
    """Receives drained output blocks; subclasses store them (memory, HDF5, a sweep point).
    Every method does nothing by default, so a sink implements only what it keeps.

    The arrays are views of the run's buffers, valid only during the call (the buffers are
    refilled next): a sink that keeps data must copy it."""

    def snapshots(self, t, step, u, v):
        pass

    def diagnostics(self, rows):
        pass

    def episodes(self, rows):
        pass

    def bounces(self, rows):
        pass

    def block(self, diagnostics, episodes, bounces, in_contact, contact_start):
        """The block's rows once more, together, after the calls above, with whether the
        bottom is on the floor at the block's end and since when (the loop's ``ev``): for
        what takes a block's samples and events in the loop's order (the first-impact
        observables, ``records.impact.ImpactStream``)."""
