"""The requests that change or inspect the world (docs/protocol.md,
"Configuring the world"), one method each, as a base class of Client: every
method builds one pb.Configure and sends it with Client.configure(), which
matches the answer by request_id and raises ServerError on a refusal.
"""

from ._proto import pb
from .images import entity_kind_value as _kind_value


def _load_map(route, car_speed, traffic, **source):
    load = pb.LoadMap(route=route, car_speed=car_speed, **source)
    if traffic is not None:
        load.traffic.CopyFrom(pb.TrafficSettings(**traffic))
    return load


class WorldRequests:
    """Mixed into Client; needs its configure(request) -> pb.Configured."""

    def _configure_world(self, **request):
        """configure(pb.Configure(**request)) -> the WorldInfo after the change."""
        return self.configure(pb.Configure(**request)).world

    def load_map_by_name(self, name, route="", car_speed=0.0, traffic=None):
        """Replaces the world with a shipped map, e.g. "tracking/hard_urban"
        (route "": its first closed route; car_speed 0: the daemon's
        --car-speed; traffic None: the daemon's --traffic-* flags, else a
        dict of TrafficSettings fields, e.g. {"cars": 20, "pedestrians": 30}).
        Returns the WorldInfo."""
        return self._configure_world(load_map=_load_map(route, car_speed, traffic, name=name))

    def load_map_text(self, text, route="", car_speed=0.0, traffic=None):
        """The same with the text of a map file (docs/maps.md)."""
        return self._configure_world(load_map=_load_map(route, car_speed, traffic, text=text))

    def spawn(self, kind, name, x, y, z, yaw_deg=0.0, snap_to_lane=False):
        """Adds a car (at rest, brake on; z ignored), a UAV (hovering; z
        above the ground, >= 0.5 m) or a pedestrian (standing; z ignored).
        kind: "car", "uav", "pedestrian" or an ENTITY_KIND_* value; name "":
        "car_<id>" / "uav_<id>" / "pedestrian_<id>". Returns the new id."""
        spawn = pb.Spawn(kind=_kind_value(kind), name=name, position=pb.Vec3(x=x, y=y, z=z),
                         yaw_deg=yaw_deg, snap_to_lane=snap_to_lane)
        return self.configure(pb.Configure(spawn=spawn)).entity_id

    def remove(self, entity_id):
        """Removes an entity (and the cameras mounted on it)."""
        return self._configure_world(remove=pb.Remove(entity_id=entity_id))

    def set_route(self, entity_id, route_name, speed):
        """A car drives one of the map's routes (WorldInfo.routes) at `speed` m/s."""
        return self._configure_world(set_route=pb.SetRoute(entity_id=entity_id, route_name=route_name, speed=speed))

    def set_waypoints(self, entity_id, points, closed, speed):
        """A car drives (a pedestrian walks) through points [(x, y), ...]:
        round and round if `closed`, else it stops at the last one."""
        waypoints = pb.Waypoints(points=[pb.Vec2(x=x, y=y) for x, y in points], closed=closed)
        return self._configure_world(set_route=pb.SetRoute(entity_id=entity_id, waypoints=waypoints, speed=speed))

    def set_conditions(self, preset="", hour=None, quality="", randomize_seed=0, randomize_every_frames=0):
        """Weather and time of day of the RGB images from the next frame on:
        preset "clear_noon", "clear_morning", "overcast", "fog", "dusk",
        "night" or "rain" ("": keep), hour in [0, 24] (None: the preset's
        own), quality "full" or "fast" ("": keep). randomize_seed != 0:
        domain randomisation instead, reproducible from the seed, new
        conditions every randomize_every_frames frames (0: each episode,
        i.e. now and at every reset/load_map). Depth, masks, boxes and the
        other channels never change with them. Returns the WorldInfo, whose
        .conditions says what is in force."""
        request = pb.SetConditions(preset=preset, quality=quality, randomize_seed=randomize_seed,
                                   randomize_every_frames=randomize_every_frames)
        if hour is not None:
            request.hour = hour
        return self._configure_world(set_conditions=request)

    def set_effects(self, **effects):
        """Camera effects from the next frame on (docs/protocol.md, "Camera
        effects"): keyword arguments named as CameraEffects' fields, e.g.
        set_effects(k1=-0.2, motion_blur=0.5, jpeg_quality=80, antialias=1,
        exposure_ev=0.5, white_balance_k=4000); the others keep their value.
        A lens (k1, k2, p1, p2, k3; OpenCV's model, also in every frame's
        camera_intrinsics) distorts every channel and the boxes alike; the
        other effects change RGB only. Returns the WorldInfo, whose .effects
        says what is in force."""
        return self._configure_world(set_effects=pb.CameraEffects(**effects))

    def set_speed(self, entity_id, speed):
        """Keeps the car's route and changes its speed; 0 stops it."""
        return self._configure_world(set_route=pb.SetRoute(entity_id=entity_id, keep_route=True, speed=speed))

    def uav_follow(self, entity_id, target_id, altitude=0.0, pitch_down_deg=0.0):
        """The UAV films `target_id` from behind and above (0: 15 m, 60 degrees)."""
        follow = pb.CommandUav.Follow(target_id=target_id, altitude=altitude, pitch_down_deg=pitch_down_deg)
        return self._configure_world(command_uav=pb.CommandUav(entity_id=entity_id, follow=follow))

    def uav_hold(self, entity_id, x, y, z, yaw_deg=0.0):
        """The UAV flies to and holds a world position and heading."""
        hold = pb.CommandUav.Hold(position=pb.Vec3(x=x, y=y, z=z), yaw_deg=yaw_deg)
        return self._configure_world(command_uav=pb.CommandUav(entity_id=entity_id, hold=hold))

    def uav_velocity(self, entity_id, vx, vy, vz, yaw_rate_deg=0.0):
        """The UAV flies a world-frame velocity (m/s) and turn rate (degrees/s)."""
        velocity = pb.CommandUav.Velocity(velocity=pb.Vec3(x=vx, y=vy, z=vz), yaw_rate_deg=yaw_rate_deg)
        return self._configure_world(command_uav=pb.CommandUav(entity_id=entity_id, velocity=velocity))

    def uav_track(self, entity_id, camera, distance=0.0, altitude=0.0):
        """Tracking in the loop: the UAV steers by the boxes that trackers of
        its camera `camera` send (send_tracker_output of clients subscribed
        to it): it holds station `distance` metres behind where the newest box
        puts the target (0: where the camera centre looks), at `altitude`
        metres (0: the current one)."""
        track = pb.CommandUav.Track(camera=camera, distance=distance, altitude=altitude)
        return self._configure_world(command_uav=pb.CommandUav(entity_id=entity_id, track=track))

    def add_camera(self, name, mounted_on="", width=320, height=180, fov_y_deg=60.0, pitch_down_deg=0.0,
                   yaw_deg=0.0, gimbal=False, offset=(0.0, 0.0, 0.0)):
        """Adds a camera on the entity called `mounted_on` (offset in its body
        frame: x forward, y left, z up), or fixed in the world at `offset`
        if mounted_on is empty. Subscribe to it by `name`."""
        x, y, z = offset
        camera = pb.AddCamera(name=name, mounted_on=mounted_on, width=width, height=height, fov_y_deg=fov_y_deg,
                              pitch_down_deg=pitch_down_deg, yaw_deg=yaw_deg, gimbal=gimbal,
                              offset=pb.Vec3(x=x, y=y, z=z))
        return self._configure_world(add_camera=camera)

    def set_camera_pose(self, camera, x, y, z, yaw_deg, pitch_down_deg=0.0):
        """Moves a camera fixed in the world (add_camera without mounted_on)
        from the next frame on: position (m), heading (degrees from east,
        counter-clockwise), pitch below the horizon (degrees)."""
        pose = pb.SetCameraPose(camera=camera, position=pb.Vec3(x=x, y=y, z=z), yaw_deg=yaw_deg,
                                pitch_down_deg=pitch_down_deg)
        return self._configure_world(set_camera_pose=pose)

    def remove_camera(self, name):
        """Removes a camera add_camera() added; its subscribers get an
        UNKNOWN_CAMERA Error."""
        return self._configure_world(remove_camera=pb.RemoveCamera(name=name))

    def reset(self):
        """Back to the loaded map's start: time 0, spawned entities and added cameras gone."""
        return self._configure_world(reset=pb.Reset())

    def get_world(self):
        """The WorldInfo: scene name, entities, cameras, routes, frame id."""
        return self._configure_world(get_world=pb.GetWorld())

    def get_map_text(self):
        """The loaded map in the canonical map text format (docs/maps.md);
        "" when the world is a scene file, not a map."""
        return self.configure(pb.Configure(get_world=pb.GetWorld(with_map_text=True))).map_text

    def list_maps(self):
        """The names load_map_by_name takes: every map under the daemon's
        --maps-dir, e.g. "tracking/easy_urban", sorted."""
        return list(self.configure(pb.Configure(list_maps=pb.ListMaps())).maps)

    def check_map(self, text):
        """The daemon's parser on map text, nothing loaded: the canonical
        text, or a ServerError naming the line ("map line N 'LINE': ...")."""
        return self.configure(pb.Configure(check_map=pb.CheckMap(text=text))).map_text

    def generate_map(self, seed=1, width=10, height=10, surroundings="desert", name="", tile_size=0.0,
                     roadside_trees=None, layout_text=""):
        """The seeded generator's map text (sim4cv_mapgen's, byte for byte);
        with layout_text, that map's roads and routes newly dressed. Nothing
        is loaded: load_map_text plays it."""
        request = pb.GenerateMap(seed=seed, width=width, height=height, surroundings=surroundings, name=name,
                                 tile_size=tile_size, layout_text=layout_text)
        if roadside_trees is not None:
            request.roadside_trees = roadside_trees
        return self.configure(pb.Configure(generate_map=request)).map_text

    def open_map(self, name):
        """The bytes of a map file under the daemon's --maps-dir (a name
        list_maps gives)."""
        return self.configure(pb.Configure(open_map=pb.OpenMap(name=name))).map_text

    def start_log(self, name, label="", overwrite=False, detach=False):
        """Starts a run log of every frame from the next one on, NAME.s4log
        under the daemon's --logs-dir (docs/logs.md); returns its path. The
        log ends when this client disconnects, unless `detach`; a cap
        (--log-max-bytes, --log-max-seconds) or a failed write ends it too,
        and the next call that reads raises ServerError saying why."""
        start = pb.StartLog(name=name, label=label, overwrite=overwrite, detach=detach)
        return self.configure(pb.Configure(start_log=start)).log_file

    def stop_log(self):
        """Stops the run log start_log began; returns its path."""
        return self.configure(pb.Configure(stop_log=pb.StopLog())).log_file

    def save_map(self, name, text, overwrite=False):
        """Writes text to NAME.map under the daemon's --maps-dir, if the
        daemon's parser accepts it; an existing file only with overwrite."""
        self.configure(pb.Configure(save_map=pb.SaveMap(name=name, text=text, overwrite=overwrite)))

    def query_road(self, x, y, count=0, step=0.0, heading_deg=None, route=""):
        """Map scenes only: the nearest lane point to (x, y) (only lanes
        within 90 degrees of heading_deg, if given; only the lanes of the
        map's route `route`, if given, its points ahead turning where it
        turns) and `count` points every `step` metres ahead of it, as a
        pb.RoadQueryResult."""
        query = pb.QueryRoad(point=pb.Vec3(x=x, y=y), count=count, step=step,
                             use_heading=heading_deg is not None, heading_deg=heading_deg or 0.0, route=route)
        return self.configure(pb.Configure(query_road=query)).road
