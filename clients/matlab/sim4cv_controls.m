function sim4cv_controls(h, entity_id, steering, throttle, brake)
% SIM4CV_CONTROLS  Drive a car: steering -1 (left) .. 1 (right), throttle and brake 0 .. 1.
%
%   sim4cv_controls(h, entity_id, steering, throttle, brake)
%
%   The car follows the controls from the next physics step until others
%   arrive (its waypoint follower stops driving it). The default scene's
%   car has id 1.
%
%   Example:
%     sim4cv_controls(h, 1, 0.1, 0.5, 0);
  sim4cv_mex('controls', h, entity_id, steering, throttle, brake);
end
