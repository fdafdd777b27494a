function world = sim4cv_add_camera(h, camera)
% SIM4CV_ADD_CAMERA  Add a camera; returns the world after the change.
%
%   world = sim4cv_add_camera(h, camera)
%
%   camera is a struct with name (required) and any of mounted_on (an
%   entity's name; '' fixed in the world), width (320), height (180),
%   fov_y_deg (60), pitch_down_deg (0), yaw_deg (0), gimbal (false), and
%   x, y, z (the mount point in the body frame, metres). Unknown fields are
%   refused with sim4cv:badArgument.
%
%   Example:
%     sim4cv_add_camera(h, struct('name', 'scout_cam', 'mounted_on', 'scout', ...
%         'width', 320, 'height', 180, 'fov_y_deg', 60, 'pitch_down_deg', 45, 'gimbal', true));
%     sim4cv_subscribe(h, 'scout_cam', {'rgb'}, 'lockstep');
  world = sim4cv_mex('add_camera', h, camera);
end
