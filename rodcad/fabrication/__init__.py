"""Fabrication as numbers: cavity and insert layouts and the masses a rod can be built at.
The solids themselves are built by :mod:`rodcad.cad`.
"""
