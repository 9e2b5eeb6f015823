"""Simulation scenarios: synthetic maps and trajectories for the subsystems' experiments."""
