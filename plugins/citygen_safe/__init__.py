"""Structure-aware facade editing (dang2014, SAFE): general grids, topological jumps and a QP sizing step."""
