"""Arm models: kinematics, collision geometry, drives and motion timing.

* :class:`Arm` (:mod:`workcell.arms.base`): the contract every arm fulfils
  (vectorised frames, inverse kinematics, collision shapes, the
  displacement bound of the conservative sweep).
* :class:`CartesianGantry` (stepper axes, S1.5), :class:`Scara` (servo,
  closed-form IK), :class:`SerialArm` (DH parameters, numerical IK),
  :class:`UrdfArm` (a URDF file: UR, Panda, ...; numerical IK, capsules
  fitted to the link meshes).
* :class:`StepperDrive`, :class:`ServoDrive` and their :class:`Profile`;
  :class:`JointTrajectory` and :func:`time_path` time joint paths.
* :func:`arm_from_dict` builds arms from a cell file's tables.
"""

from workcell.arms._common import DriveArm, time_path
from workcell.arms.base import Arm, LinkShape
from workcell.arms.gantry import CartesianGantry
from workcell.arms.profiles import Drive, Profile, ServoDrive, StepperDrive
from workcell.arms.scara import Scara
from workcell.arms.serial import SerialArm
from workcell.arms.spec import ARM_TYPES, arm_from_dict
from workcell.arms.trajectory import JointTrajectory, Segment
from workcell.arms.urdf import UrdfArm

__all__ = [
    "ARM_TYPES",
    "Arm",
    "CartesianGantry",
    "Drive",
    "DriveArm",
    "JointTrajectory",
    "LinkShape",
    "Profile",
    "Scara",
    "Segment",
    "SerialArm",
    "ServoDrive",
    "StepperDrive",
    "UrdfArm",
    "arm_from_dict",
    "time_path",
]
