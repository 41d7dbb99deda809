"""The exhaustive joint-state search, compiled: classes of schedules by the cells allowed to change."""
