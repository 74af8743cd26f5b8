"""An AGV among moving obstacles: certainty grid, 2-bit local map, quadtree, t-second check."""
