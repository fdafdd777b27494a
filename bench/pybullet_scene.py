"""The default scene of sim4cvd mirrored in pybullet DIRECT, for bench/bench_vs_pybullet.py.

What it holds (against sim4cvd's default scene, server/sim/default_scene.cpp): pybullet_data's
textured plane.urdf scaled to a 300 m square (ours: a 300 m ground), the road loop as 48 flat
dark boxes 8 m wide (ours: an asphalt road mesh with lane markings), the same 12 buildings as
static boxes (ours: boxes with facades), a box car (1,200 kg chassis, four cylinder wheels on
motorised revolute joints, 6 m/s, straight along the south road; ours: a btRaycastVehicle car
driving the loop) and the walkers as capsule bodies with a sphere head moved kinematically
along the sidewalk at 1.4 m/s (ours: walkers with packaged meshes walking waypoints). One
frame: 8 x stepSimulation (1/240 s), then getCameraImage with TinyRenderer (DIRECT has no GL,
pybullet's default light, no shadows) from 15 m above the car, 60 deg down, 60 deg vertical
field of view: RGBA, depth and segmentation mask as numpy arrays.
"""

import math

FRAME_HZ, PHYSICS_HZ = 30, 240
UAV_ALTITUDE, CAMERA_PITCH_DEG, FOV_Y_DEG = 15.0, 60.0, 60.0
WALKER_SPEED = 1.4
# The default scene's buildings: centre x, y, half x, half y, height, yaw (deg).
BUILDINGS = ((-30, 0, 8, 10, 12, 0), (0, 0, 10, 8, 18, 0), (30, 0, 8, 10, 9, 0), (-20, -62, 8, 6, 14, 0),
             (20, -62, 10, 6, 10, 0), (75, -20, 6, 10, 16, 0), (75, 20, 6, 8, 8, 15), (20, 62, 10, 6, 20, 0),
             (-20, 62, 8, 6, 11, 0), (-75, 15, 6, 10, 13, 0), (-75, -25, 6, 8, 9, -10), (55, -60, 5, 5, 7, 30))


def road_loop():
    """The default scene's 48 road centre points: straights at y = -40, x = 60, y = 40 and x = -60
    (10 m apart) joined by 20 m arcs (15 degree steps), counter-clockwise from (-40, -40)."""
    points = []
    for (x0, y0, dx, dy), (cx, cy, a0) in zip(((-40, -40, 10, 0), (60, -20, 0, 10), (40, 40, -10, 0),
                                               (-60, 20, 0, -10)),
                                              ((40, -20, -90), (40, 20, 0), (-40, 20, 90), (-40, -20, 180))):
        points += [(x0 + k * dx, y0 + k * dy) for k in range(9 if dx else 5)]
        points += [(cx + 20 * math.cos(math.radians(a0 + 15 * k)), cy + 20 * math.sin(math.radians(a0 + 15 * k)))
                   for k in range(1, 6)]
    return points


def walker_starts(count):
    """Walkers on the south sidewalk ahead of the car (y = -46), spread over 60 m."""
    return [(-38.0 + 60.0 * i / max(1, count), -46.0 - (i % 2)) for i in range(count)]



class PybulletScene:
    """The mirror scene in a DIRECT pybullet client of its own (see the module doc)."""

    def __init__(self, pybullet, pybullet_data, width, height, walkers):
        p = self.p = pybullet
        self.cid = p.connect(p.DIRECT)
        p.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=self.cid)
        p.setGravity(0, 0, -9.81, physicsClientId=self.cid)
        p.setTimeStep(1.0 / PHYSICS_HZ, physicsClientId=self.cid)
        p.loadURDF("plane.urdf", globalScaling=1.5, physicsClientId=self.cid)  # 300 m square like ours
        points = road_loop()
        for (x0, y0), (x1, y1) in zip(points, points[1:] + points[:1]):
            length = math.hypot(x1 - x0, y1 - y0)
            self.box((length / 2 + 0.5, 4.0, 0.01), ((x0 + x1) / 2, (y0 + y1) / 2, 0.01),
                     math.atan2(y1 - y0, x1 - x0), (0.25, 0.25, 0.27, 1), collide=False)
        for cx, cy, hx, hy, h, yaw in BUILDINGS:
            self.box((hx, hy, h / 2), (cx, cy, h / 2), math.radians(yaw), (0.7, 0.62, 0.55, 1))
        self.car = self.make_car()
        self.walkers = [self.make_walker(x, y) for x, y in walker_starts(walkers)]
        self.walker_starts = walker_starts(walkers)
        self.step_count = 0
        self.width, self.height = width, height
        self.projection = p.computeProjectionMatrixFOV(FOV_Y_DEG, width / height, 0.1, 500.0)

    def box(self, half, position, yaw, colour, collide=True):
        p = self.p
        visual = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=colour, physicsClientId=self.cid)
        collision = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=self.cid) if collide else -1
        return p.createMultiBody(0, collision, visual, position, p.getQuaternionFromEuler((0, 0, yaw)),
                                 physicsClientId=self.cid)

    def make_car(self):
        p, cid = self.p, self.cid
        chassis_v = p.createVisualShape(p.GEOM_BOX, halfExtents=(2.25, 0.9, 0.5), rgbaColor=(0.8, 0.1, 0.1, 1),
                                        physicsClientId=cid)
        chassis_c = p.createCollisionShape(p.GEOM_BOX, halfExtents=(2.25, 0.9, 0.5), physicsClientId=cid)
        wheel_v = p.createVisualShape(p.GEOM_CYLINDER, radius=0.35, length=0.25, rgbaColor=(0.1, 0.1, 0.1, 1),
                                      physicsClientId=cid)
        wheel_c = p.createCollisionShape(p.GEOM_CYLINDER, radius=0.35, height=0.25, physicsClientId=cid)
        axle = p.getQuaternionFromEuler((math.pi / 2, 0, 0))  # cylinder axis (z) along the car's y
        wheels = [(1.4, 0.95), (1.4, -0.95), (-1.4, 0.95), (-1.4, -0.95)]
        car = p.createMultiBody(
            1200, chassis_c, chassis_v, (-40.0, -42.0, 0.9), (0, 0, 0, 1),
            linkMasses=[20] * 4, linkCollisionShapeIndices=[wheel_c] * 4, linkVisualShapeIndices=[wheel_v] * 4,
            linkPositions=[(x, y, -0.55) for x, y in wheels], linkOrientations=[axle] * 4,
            linkInertialFramePositions=[(0, 0, 0)] * 4, linkInertialFrameOrientations=[(0, 0, 0, 1)] * 4,
            linkParentIndices=[0] * 4, linkJointTypes=[p.JOINT_REVOLUTE] * 4, linkJointAxis=[(0, 0, 1)] * 4,
            physicsClientId=cid)
        # Wheel spin about the cylinder axis; forward (+x) needs a negative rate about +y = axle z.
        p.setJointMotorControlArray(car, range(4), p.VELOCITY_CONTROL, targetVelocities=[-6.0 / 0.35] * 4,
                                    forces=[800] * 4, physicsClientId=cid)
        return car

    def make_walker(self, x, y):
        p, cid = self.p, self.cid
        body = p.createVisualShape(p.GEOM_CAPSULE, radius=0.25, length=1.1, rgbaColor=(0.2, 0.3, 0.6, 1),
                                   physicsClientId=cid)
        head_v = p.createVisualShape(p.GEOM_SPHERE, radius=0.12, rgbaColor=(0.9, 0.7, 0.6, 1), physicsClientId=cid)
        collision = p.createCollisionShape(p.GEOM_CAPSULE, radius=0.25, height=1.1, physicsClientId=cid)
        return p.createMultiBody(0, collision, body, (x, y, 0.8), (0, 0, 0, 1), linkMasses=[0],
                                 linkCollisionShapeIndices=[-1], linkVisualShapeIndices=[head_v],
                                 linkPositions=[(0, 0, 0.95)], linkOrientations=[(0, 0, 0, 1)],
                                 linkInertialFramePositions=[(0, 0, 0)], linkInertialFrameOrientations=[(0, 0, 0, 1)],
                                 linkParentIndices=[0], linkJointTypes=[p.JOINT_FIXED], linkJointAxis=[(0, 0, 1)],
                                 physicsClientId=cid)

    def step(self):
        """One frame: 8 physics steps with the walkers moved, then the camera image."""
        p, cid = self.p, self.cid
        for _ in range(PHYSICS_HZ // FRAME_HZ):
            self.step_count += 1
            walked = WALKER_SPEED * self.step_count / PHYSICS_HZ
            for walker, (x, y) in zip(self.walkers, self.walker_starts):
                p.resetBasePositionAndOrientation(walker, (x + walked, y, 0.8), (0, 0, 0, 1), physicsClientId=cid)
            p.stepSimulation(physicsClientId=cid)
        (cx, cy, cz), orientation = p.getBasePositionAndOrientation(self.car, physicsClientId=cid)
        yaw = p.getEulerFromQuaternion(orientation)[2]
        back = UAV_ALTITUDE / math.tan(math.radians(CAMERA_PITCH_DEG))
        eye = (cx - back * math.cos(yaw), cy - back * math.sin(yaw), cz + UAV_ALTITUDE)
        view = p.computeViewMatrix(eye, (cx, cy, cz), (0, 0, 1))
        return p.getCameraImage(self.width, self.height, view, self.projection, renderer=p.ER_TINY_RENDERER,
                                physicsClientId=cid)

    def check_image(self, width, height, rgb, depth, mask):
        """getCameraImage's answer is what was asked for and shows the scene (not an empty view)."""
        import numpy as np
        rgb, mask = np.asarray(rgb), np.asarray(mask)
        if (width, height) != (self.width, self.height) or rgb.shape[:2] != (height, width):
            raise RuntimeError("pybullet returned a %dx%d image for %dx%d" % (width, height, self.width, self.height))
        if len(np.unique(mask)) < 4:
            raise RuntimeError("pybullet's mask shows %s only: the camera misses the scene" % np.unique(mask))

    def close(self):
        self.p.disconnect(physicsClientId=self.cid)

