"""Experiments that reproduce the papers and the quick demos registered with indoorloc.demo."""
