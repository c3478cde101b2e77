"""Figures of scenarios and plans (Agg backend)."""
