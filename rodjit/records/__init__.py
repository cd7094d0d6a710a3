"""What a run produces, as plain records: the column lists, the ``Sink`` protocol through
which a run hands out its rows, the bounce table, the run statistics, the diagnostics'
running extremes and the in-memory ``Result``.

This floor sits above ``stepping`` (whose ``layout`` names the columns) and below
``output``, ``driver`` and ``sweeps``, which all build on it: a writer, the run driver and a
sweep point share one definition of each record instead of rebuilding it.
"""
