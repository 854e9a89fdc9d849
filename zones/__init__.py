"""zones: SDL, the zone model and the run-time zone protocol (SEEDS.md S2.5-S2.7)."""
