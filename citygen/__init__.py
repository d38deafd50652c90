"""citygen: procedural cities of detailed buildings from real footprints, written as USD stages."""

__version__ = "0.1.0"
