"""Experiments: the papers' plans, the runner, run tables and their statistics."""
