"""Python orchestration: runs in progress, results, the ``simulate`` entry point."""
