"""Rod catalogs: the data model (:mod:`.model`, no CAD), the file format
(:mod:`.spec`) and loader (:mod:`.loader`), and what is derived from the rods' solids:
joint limits (:mod:`.limits`) and mass ranges (:mod:`.massrange`), disk-cached
(:mod:`.cache`) with precomputed seeds for the shipped catalogs.
"""
