function world = sim4cv_uav_follow(h, uav, target, altitude, pitch_down_deg)
% SIM4CV_UAV_FOLLOW  A UAV films an entity from behind and above it.
%
%   world = sim4cv_uav_follow(h, uav_id, target_id)
%   world = sim4cv_uav_follow(h, uav_id, target_id, altitude, pitch_down_deg)
%
%   altitude in metres above the target (0: 15), pitch_down_deg the camera
%   pitch the station is worked out for (0: 60) - what the default scene's
%   UAV does.
%
%   Example:
%     sim4cv_uav_follow(h, 2, 1);   % the scene's UAV follows the car again
%
%   See also SIM4CV_UAV_VELOCITY.
  if nargin < 4, altitude = 0; end
  if nargin < 5, pitch_down_deg = 0; end
  world = sim4cv_mex('uav_follow', h, uav, target, altitude, pitch_down_deg);
end
