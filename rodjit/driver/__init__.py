"""Running one simulation: a run in progress (``run``), streaming it to a run file
(``files``: ``run_to_file``, ``resume_file``), the in-memory ``simulate``, and the clean
stop on SIGINT/SIGTERM (``signals``)."""
