"""CAD: the only package that imports build123d or OCP. Rod and frame solids, booleans,
collision queries, STEP/STL writing.
"""
