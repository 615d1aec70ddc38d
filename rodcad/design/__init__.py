"""Design files and chain design: the design-file model and loader, targets, planning
(rods laid on the target, types and stops), mass design, and a chandelier's layout.
"""
