"""Layer-stack facade rulesets (Ilčík et al. 2015, "Layer-Based Procedural Design of Facades").

A ruleset is a stack of layers, each the outer product of a horizontal and a vertical *pattern* (regular
expressions with counters, §3.2--3.4). The solver (§5) instantiates the patterns (candidate generation), aligns
the layers by a shortest path through the alignment decision network, and sizes every letter with a constrained
least-squares problem, separately per direction; the outer product gives the layout.
"""
