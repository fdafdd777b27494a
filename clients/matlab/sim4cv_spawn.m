function id = sim4cv_spawn(h, kind, name, x, y, z, yaw_deg)
% SIM4CV_SPAWN  Add a car, a UAV or a pedestrian; returns its entity id.
%
%   id = sim4cv_spawn(h, kind, name, x, y, z)
%   id = sim4cv_spawn(h, kind, name, x, y, z, yaw_deg)
%
%   kind is 'car' (stands with its brake on; z ignored), 'uav' (hovers; z
%   above the ground, at least 0.5 m) or 'pedestrian'. name '' lets the
%   daemon choose ('uav_<id>'). Positions are world metres, yaw_deg
%   counter-clockwise from east.
%
%   Example:
%     scout = sim4cv_spawn(h, 'uav', 'scout', 0, -20, 12);
%     sim4cv_uav_velocity(h, scout, 1, 0, 0);
  if nargin < 7, yaw_deg = 0; end
  id = sim4cv_mex('spawn', h, kind, name, x, y, z, yaw_deg);
end
