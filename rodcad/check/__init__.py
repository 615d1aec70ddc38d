"""The round trip after manual edits: ``rodcad check OUTDIR [--rebalance]``.

``built`` reads an earlier build's design.json, ``types`` its catalog and rod types,
``measure`` re-reads and measures its rods (solids through :mod:`rodcad.cad.reread`),
``recheck`` re-simulates the chain, ``rebalance`` re-designs the unedited rods around the
edited ones, and ``write`` writes the preview and the re-balanced output folder.
"""
