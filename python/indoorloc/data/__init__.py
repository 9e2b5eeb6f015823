"""Packaged data files of indoorloc (read with :mod:`importlib.resources`).

- ``warehouse.geojson``: the warehouse road network of El Mokhtari et al., "Indoor Localization
  by Particle Map Matching" (paper 000, Fig. 2), re-digitised from the text as 26 axis-aligned
  segments with ids 1..26 in planar metres; read it with
  :func:`indoorloc.io.warehouse_segments`. Layout, numbering and assumptions:
  ``docs/mapmatch_warehouse.md``.
"""
