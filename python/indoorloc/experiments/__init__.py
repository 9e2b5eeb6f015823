"""Experiments that reproduce the papers and the quick demos registered with indoorloc.registry (run by indoorloc.demo)."""
