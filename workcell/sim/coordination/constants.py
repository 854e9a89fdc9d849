"""Constants of the centralized coordinator."""

__all__ = ["CAUSE_KINDS"]

CAUSE_KINDS: tuple[str, ...] = (
    "arm_failed",
    "part_missing",
    "deadlock",
    "insertion",
    "predecessor",
    "arm_out",
    "stall",
)
"""The categories of a failed task's cause (``SimResult.tasks_frame()``
column ``cause_kind``): every capable arm failed; a part never came; a
deadlock (with its wait-for cycle); its insertion failed; a predecessor
could not run; its arm failed with re-solving off; the run stalled (an arm
with work, no stop in force and no event pending: a bug of the simulator)."""
