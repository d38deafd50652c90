"""Inverse procedural modelling (wu2014): CMP facade import and split-grammar extraction."""
