"""The files a run writes: atomic text and JSON, history and summary, crash-safe fields."""

__all__ = ["files", "results", "fields"]
