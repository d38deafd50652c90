"""Geometry: terminal regions of facade layouts turned into meshes and instances."""
