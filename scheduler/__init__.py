"""scheduler: the multi-arm task scheduler (SEEDS.md S2.10-S2.12)."""
