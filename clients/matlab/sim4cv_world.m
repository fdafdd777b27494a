function world = sim4cv_world(h)
% SIM4CV_WORLD  The world's entities, cameras and routes.
%
%   world = sim4cv_world(h)
%
%   world has scene_name, frame_id, entities (Nx1 struct array: id, name,
%   kind 'car'|'uav'|'pedestrian'), cameras (Nx1 struct array: name, width,
%   height, fov_y_deg, mounted_on) and routes (cell array, map scenes).
%
%   Example:
%     w = sim4cv_world(h);
%     car_id = w.entities(strcmp({w.entities.name}, 'car')).id;
%     cameras = {w.cameras.name};
  world = sim4cv_mex('world', h);
end
