function world = sim4cv_uav_velocity(h, uav, vx, vy, vz, yaw_rate_deg)
% SIM4CV_UAV_VELOCITY  A UAV flies a world-frame velocity (m/s) from now on.
%
%   world = sim4cv_uav_velocity(h, uav_id, vx, vy, vz)
%   world = sim4cv_uav_velocity(h, uav_id, vx, vy, vz, yaw_rate_deg)
%
%   vx east, vy north, vz up, each in [-20, 20]; yaw_rate_deg turns it
%   counter-clockwise, in [-180, 180]. This replaces any follow or hold
%   order (the scene's UAV stops following the car).
%
%   Example:
%     sim4cv_uav_velocity(h, 2, 3, 0, 0);   % fly east at 3 m/s
%
%   See also SIM4CV_UAV_FOLLOW.
  if nargin < 6, yaw_rate_deg = 0; end
  world = sim4cv_mex('uav_velocity', h, uav, vx, vy, vz, yaw_rate_deg);
end
