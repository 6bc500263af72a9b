"""A differential-drive robot with two casters and a pan/tilt camera mount.

The URDF is generated from ``configs`` (``robot`` section) so every dimension lives in one
place; the wheels touch the floor through PyBullet contacts and are driven by velocity motors
(their targets from :mod:`stsf_gym.envs.drive_controller`). The chassis rests level on its
wheels and sprung, frictionless casters: the camera's true pose is ``true_pose`` composed with
:meth:`DiffDriveRobot.robot_from_camera` to a fraction of a millimetre and milliradian.
The base frame sits on the wheel axle midpoint; ``true_pose`` is its floor position and yaw.
Every link's centre of mass is at its frame origin (PyBullet reports base poses at the centre
of mass), which also keeps the robot's centre of mass low.
"""

from __future__ import annotations

import math

import numpy as np

from stsf_gym.camera_model import LINK_FROM_OPTICAL, PanTiltMount, pose_matrix, rot_z
from stsf_gym.envs.config import RobotConfig
from stsf_gym.envs.simulator import Simulator, cache_file
from stsf_gym.geometry import clamp

CASTER_FRACTION = 0.45  # caster sphere radius as a fraction of the wheel radius
BODY_CLEARANCE = 0.05  # floor to body bottom (m)
WHEEL_WIDTH = 0.03
# The casters touch the floor through a stiff, critically damped spring (a rubber-tyred caster),
# frictionless: with rigid contacts four wheels on a floor are statically indeterminate and the
# solver may leave the driven wheels unloaded; lifted clear, the chassis tips onto one caster
# and rocks to the other on every reversal. Loaded by a spring, the driven wheels carry the
# weight and the chassis stays level to about 0.1 mrad under the controller's accelerations.
CASTER_CONTACT = {"contactStiffness": 3.0e5, "contactDamping": 2.5e3}  # N/m, N s/m


def _box_inertia(mass: float, x: float, y: float, z: float) -> str:
    ixx, iyy, izz = (mass / 12 * (b * b + c * c) for b, c in ((y, z), (x, z), (x, y)))
    return f'<inertia ixx="{ixx:.6f}" iyy="{iyy:.6f}" izz="{izz:.6f}" ixy="0" ixz="0" iyz="0"/>'


def robot_urdf(cfg: RobotConfig) -> str:
    """URDF text of the robot described by ``cfg``."""
    r, half_b, body_r, body_h = (
        cfg.wheel_radius,
        cfg.wheelbase / 2,
        cfg.body_radius,
        cfg.body_height,
    )
    body_z = BODY_CLEARANCE + body_h / 2 - r
    caster_r = CASTER_FRACTION * r
    caster_x = body_r - caster_r - 0.02
    mast_top = cfg.camera_height - r
    mast_h = mast_top - (body_z + body_h / 2)
    wheel_mass, head_mass = 0.5, 0.3

    def link(
        name: str,
        mass: float,
        geometry: str,
        origin: str,
        color: str,
        dims,
        collision: str | None = None,
    ) -> str:
        shape = f"<origin {origin}/><geometry>{geometry}</geometry>"
        return (
            f'<link name="{name}"><inertial><origin xyz="0 0 0"/><mass value="{mass}"/>'
            f"{_box_inertia(mass, *dims)}</inertial>"
            f'<visual>{shape}<material name="{name}_m"><color rgba="{color}"/></material></visual>'
            f"<collision>{collision or shape}</collision></link>"
        )

    def joint(name: str, kind: str, child: str, xyz, axis="0 0 1", parent="base_link", lim=None):
        limit = (
            f'<limit lower="{-lim:.6f}" upper="{lim:.6f}" effort="50" velocity="3"/>'
            if lim is not None
            else ""
        )
        return (
            f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz[0]:.6f} {xyz[1]:.6f} {xyz[2]:.6f}"/><axis xyz="{axis}"/>{limit}'
            "</joint>"
        )

    wheel_geom = f'<cylinder radius="{r}" length="{WHEEL_WIDTH}"/>'
    wheel_origin = f'xyz="0 0 0" rpy="{math.pi / 2:.6f} 0 0"'
    # A sphere touches the floor in one clean point; Bullet's cylinder-box contacts jitter
    # and make the wheels creep sideways, which no encoder could see.
    wheel_contact = f'<origin xyz="0 0 0"/><geometry><sphere radius="{r}"/></geometry>'
    parts = [
        '<?xml version="1.0"?>',
        '<robot name="stsf_diff_drive">',
        link(
            "base_link",
            cfg.mass,
            f'<cylinder radius="{body_r}" length="{body_h}"/>',
            f'xyz="0 0 {body_z:.6f}"',
            "0.55 0.57 0.6 1",
            (2 * body_r, 2 * body_r, body_h),
        ),
        link(
            "left_wheel",
            wheel_mass,
            wheel_geom,
            wheel_origin,
            "0.1 0.1 0.1 1",
            (r, r, r),
            wheel_contact,
        ),
        link(
            "right_wheel",
            wheel_mass,
            wheel_geom,
            wheel_origin,
            "0.1 0.1 0.1 1",
            (r, r, r),
            wheel_contact,
        ),
        joint("left_wheel_joint", "continuous", "left_wheel", (0, half_b, 0), "0 1 0"),
        joint("right_wheel_joint", "continuous", "right_wheel", (0, -half_b, 0), "0 1 0"),
    ]
    for name, x in (("front_caster", caster_x), ("rear_caster", -caster_x)):
        geom = f'<sphere radius="{caster_r:.6f}"/>'
        parts.append(link(name, 0.2, geom, 'xyz="0 0 0"', "0.2 0.2 0.2 1", (caster_r,) * 3))
        parts.append(joint(f"{name}_joint", "fixed", name, (x, 0, caster_r - r)))
    mast_geom = f'<box size="0.04 0.04 {mast_h:.6f}"/>'
    mast_origin = f'xyz="0 0 {-mast_h / 2:.6f}"'
    head_geom = '<box size="0.06 0.08 0.05"/>'
    parts += [
        link("pan_link", 0.5, mast_geom, mast_origin, "0.3 0.3 0.35 1", (0.04, 0.04, mast_h)),
        joint(
            "pan_joint",
            "revolute",
            "pan_link",
            (cfg.camera_forward, 0, mast_top),
            lim=math.radians(cfg.pan_limit_deg),
        ),
        link(
            "camera_link",
            head_mass,
            head_geom,
            'xyz="-0.035 0 0"',
            "0.1 0.1 0.12 1",
            (0.06, 0.08, 0.05),
        ),
        joint(
            "tilt_joint",
            "revolute",
            "camera_link",
            (0, 0, 0),
            "0 -1 0",
            parent="pan_link",
            lim=math.radians(cfg.tilt_limit_deg),
        ),
        "</robot>",
    ]
    return "\n".join(parts)


class DiffDriveRobot:
    """The robot in one simulator: drive, pan/tilt, pose, wheel angles, contacts."""

    def __init__(self, sim: Simulator, cfg: RobotConfig) -> None:
        self.sim, self.cfg = sim, cfg
        c = sim.client
        urdf = cache_file("robot.urdf", robot_urdf(cfg).encode())
        self.body = c.loadURDF(
            str(urdf), [0, 0, cfg.wheel_radius], flags=c.URDF_USE_INERTIA_FROM_FILE
        )
        joints = {
            c.getJointInfo(self.body, j)[1].decode(): j for j in range(c.getNumJoints(self.body))
        }
        self.wheels = [joints["left_wheel_joint"], joints["right_wheel_joint"]]
        self.pan_tilt = [joints["pan_joint"], joints["tilt_joint"]]
        self.camera_link = joints["tilt_joint"]
        for caster in ("front_caster_joint", "rear_caster_joint"):
            c.changeDynamics(
                self.body,
                joints[caster],
                lateralFriction=0.0,
                rollingFriction=0.0,
                spinningFriction=0.0,
                **CASTER_CONTACT,
            )
        for wheel in self.wheels:
            c.changeDynamics(self.body, wheel, lateralFriction=cfg.wheel_friction)
        self.pan_tilt_limits = np.radians([cfg.pan_limit_deg, cfg.tilt_limit_deg])
        # the motors' last targets: PyBullet keeps a target until told another, so the same
        # one again (most of a step's six substeps, the ramp over) need not be sent
        self._sent: dict[str, list[float]] = {}

    def reset(self, pose: tuple[float, float, float], pan: float, tilt: float) -> None:
        """Place the robot at floor pose (x, y, yaw), at rest, with the mount at (pan, tilt)."""
        c = self.sim.client
        x, y, yaw = pose
        c.resetBasePositionAndOrientation(
            self.body, [x, y, self.cfg.wheel_radius], c.getQuaternionFromEuler([0, 0, yaw])
        )
        c.resetBaseVelocity(self.body, [0, 0, 0], [0, 0, 0])
        for joint in self.wheels:
            c.resetJointState(self.body, joint, 0.0, 0.0)
        for joint, angle in zip(self.pan_tilt, (pan, tilt), strict=True):
            c.resetJointState(self.body, joint, angle, 0.0)
        self._sent.clear()
        self.drive(0.0, 0.0)
        self.point_camera(pan, tilt)

    def teleport(self, dx: float, dy: float, dyaw: float) -> None:
        """Move the base by (dx, dy) (world, m) and turn it by ``dyaw`` (rad) about its vertical
        axis, keeping its velocity in its own frame and every joint's state: the wheel encoders
        do not notice (a kidnapped robot)."""
        c = self.sim.client
        position, orientation = c.getBasePositionAndOrientation(self.body)
        turn = c.getQuaternionFromEuler([0.0, 0.0, dyaw])
        _, orientation = c.multiplyTransforms([0, 0, 0], turn, [0, 0, 0], orientation)
        c.resetBasePositionAndOrientation(
            self.body, [position[0] + dx, position[1] + dy, position[2]], orientation
        )
        rotation = rot_z(dyaw)
        linear, angular = c.getBaseVelocity(self.body)
        c.resetBaseVelocity(self.body, (rotation @ linear).tolist(), (rotation @ angular).tolist())

    def drive(self, v: float, w: float) -> None:
        """Command forward speed ``v`` (m/s) and yaw rate ``w`` (rad/s) to the wheel motors."""
        half_b, r = self.cfg.wheelbase / 2, self.cfg.wheel_radius
        targets = [(v - w * half_b) / r, (v + w * half_b) / r]
        if self._sent.get("wheels") == targets:
            return
        self._sent["wheels"] = targets
        self.sim.client.setJointMotorControlArray(
            self.body,
            self.wheels,
            self.sim.client.VELOCITY_CONTROL,
            targetVelocities=targets,
            forces=[self.cfg.wheel_max_torque] * 2,
        )

    def point_camera(self, pan: float, tilt: float) -> None:
        """Servo the mount to (pan, tilt) radians, clipped to its limits."""
        pan_limit, tilt_limit = self.pan_tilt_limits.tolist()
        targets = [clamp(float(pan), pan_limit), clamp(float(tilt), tilt_limit)]
        if self._sent.get("mount") == targets:
            return
        self._sent["mount"] = targets
        self.sim.client.setJointMotorControlArray(
            self.body,
            self.pan_tilt,
            self.sim.client.POSITION_CONTROL,
            targetPositions=targets,
            forces=[50.0, 50.0],
        )

    def floor_pose(self) -> np.ndarray:
        """True [x, y, yaw] of the base frame (world, metres and radians)."""
        c = self.sim.client
        position, orientation = c.getBasePositionAndOrientation(self.body)
        return np.array([position[0], position[1], c.getEulerFromQuaternion(orientation)[2]])

    def wheel_angles(self) -> np.ndarray:
        """The wheels' joint angles (rad), [left, right]."""
        states = self.sim.client.getJointStates(self.body, self.wheels)
        return np.array([s[0] for s in states])

    def mount_angles(self) -> np.ndarray:
        """Measured (pan, tilt) of the mount in radians."""
        states = self.sim.client.getJointStates(self.body, self.pan_tilt)
        return np.array([s[0] for s in states])

    def camera_pose(self) -> np.ndarray:
        """World-from-camera 4x4 (OpenCV axes) of the camera as simulated now."""
        c = self.sim.client
        state = c.getLinkState(self.body, self.camera_link, computeForwardKinematics=True)
        rotation = np.array(c.getMatrixFromQuaternion(state[5])).reshape(3, 3)
        return pose_matrix(*state[4], rotation @ LINK_FROM_OPTICAL)

    def camera_velocity(self) -> tuple[np.ndarray, np.ndarray]:
        """World linear (m/s) and angular (rad/s) velocity of the camera now."""
        state = self.sim.client.getLinkState(
            self.body, self.camera_link, computeLinkVelocity=1, computeForwardKinematics=True
        )
        return np.array(state[6]), np.array(state[7])

    def robot_from_camera(self, pan: float, tilt: float) -> np.ndarray:
        """Nominal robot-from-camera 4x4 (OpenCV axes) for mount angles: kinematics only.

        The robot frame is on the floor below the axle midpoint, x forward, z up.
        """
        return self.mount(pan, tilt)

    @property
    def mount(self) -> PanTiltMount:
        """The camera's pan-tilt head on the robot (nominal kinematics)."""
        return PanTiltMount(self.cfg.camera_forward, 0.0, self.cfg.camera_height)

    def in_collision(self, ignore: set[int]) -> bool:
        """Whether the robot touches any body other than those in ``ignore`` (the floor)."""
        return any(
            contact[2] not in ignore
            for contact in self.sim.client.getContactPoints(bodyA=self.body)
        )
