"""The catalog's hardware at a net's nodes and its rods, as numbers: hubs or points, hub
mass, swing and socket offsets, net rods' mass ranges (:mod:`.node`), and a bent rod's arc,
mass and centre of mass in closed form (:mod:`.bend`).
"""
