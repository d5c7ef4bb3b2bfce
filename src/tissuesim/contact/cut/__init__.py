"""Contact surfaces of cut bodies (virtual node cuts, 2D and 3D): the cut faces' surface held a
gap inside each side, where cuts meet, slivers and thin pieces, pairs that touch at rest, and
the kerf opened ahead of a blade in contact."""
