"""USD output: stage authoring (Sdf level, for speed), materials, validation."""
