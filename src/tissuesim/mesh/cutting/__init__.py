"""Cutting a simplex mesh by the virtual node algorithm (``virtual_nodes.py``): its cuts, a
plane bounded by a polygon (``planar_cut.py``) or the surface a blade swept (``swept_cut.py``),
the closed-form simplex splits (``plane_split.py``), which node slots stay one node
(``node_groups.py``), the batched polygon clip (``polygon_clip.py``), the crumbs a cut frees
(``crumbs.py``) and the cells cut ahead of a blade (``cut_ahead.py``)."""
