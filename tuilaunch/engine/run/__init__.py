"""Running a Plan: the supervisor, process output, the engine thread."""
