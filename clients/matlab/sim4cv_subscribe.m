function sim4cv_subscribe(h, camera, channels, delivery)
% SIM4CV_SUBSCRIBE  Start receiving the frames of one camera.
%
%   sim4cv_subscribe(h, camera, channels)
%   sim4cv_subscribe(h, camera, channels, delivery)
%
%   camera is a camera name (the default scene has 'uav', 'car_front' and
%   'car_chase'; over shared memory only the ring's camera, 'uav' unless
%   sim4cvd --shm-camera says otherwise). channels is a cell array of
%   'rgb', 'depth', 'mask', 'boxes', 'semantic', 'normals', 'flow', 'albedo' (over
%   shared memory only what --shm-channels carries; boxes always come).
%   delivery is 'lockstep' (default: the simulation waits for each of your
%   steps), 'newest' or 'on_request' (then use sim4cv_frame(h, 'newest')).
%
%   Example:
%     sim4cv_subscribe(h, 'uav', {'rgb', 'depth', 'mask', 'boxes'}, 'lockstep');
%
%   See also SIM4CV_FRAME, SIM4CV_STEP.
  if nargin < 4, delivery = 'lockstep'; end
  sim4cv_mex('subscribe', h, camera, channels, delivery);
end
