function mean_iou = mosse_tracker(address, frames, show)
% MOSSE_TRACKER  A MOSSE correlation-filter tracker flying a UAV in the loop.
%
%   mean_iou = mosse_tracker(address, frames)
%   mean_iou = mosse_tracker(address, frames, show)
%
%   Connects to sim4cvd at address (e.g. 'shm:///sim4cv', 'tcp://127.0.0.1:5555'),
%   subscribes to the camera 'uav' in lockstep and tracks the car the UAV
%   films: the filter (Bolme et al., "Visual Object Tracking using Adaptive
%   Correlation Filters", CVPR 2010; clients/matlab/trax/mosse.m, the same
%   tracker sim4cv runs as octave:clients/matlab/trax/mosse.m) starts from
%   the first frame's ground-truth box of the car. Each frame it sends its box
%   (sim4cv_send_box) and steers the UAV (sim4cv_uav_velocity, which ends
%   the UAV's built-in follow order) with a proportional visual servo that
%   moves the box centre to the image centre. It prints per frame the rate
%   and the IoU with the ground-truth box, and returns the mean IoU.
%   show true draws the frames with both boxes (default false: headless).
%
%   Example (sim4cvd --shm-name sim4cv --mode lockstep running):
%     addpath('clients/matlab', 'clients/matlab/examples', 'build/clients/matlab');
%     iou = mosse_tracker('shm:///sim4cv', 300);
  if nargin < 3, show = false; end
  if ~exist('mosse', 'file')                         % clients/matlab/trax, next to this folder
    addpath(fullfile(fileparts(fileparts(mfilename('fullpath'))), 'trax'));
  end
  servo_gain = 1.5;     % 1/s: m/s of UAV velocity per metre of offset on the ground
  h = sim4cv_connect(address, 'octave-mosse');
  world = sim4cv_world(h);
  uav = world.entities(strcmp({world.entities.name}, 'uav')).id;
  target = world.entities(strcmp({world.entities.name}, 'car')).id;
  cleanup = onCleanup(@() finish(h, uav, target));   % the UAV follows the car again, then close
  sim4cv_subscribe(h, 'uav', {'rgb', 'boxes'}, 'lockstep');

  f = sim4cv_frame(h, 'step');
  truth = target_box(f, target);
  if isempty(truth), error('mosse_tracker:noTarget', 'the car (entity %d) is not in the first frame', target); end
  tracker = mosse(struct('eta', 0.125, 'sigma', 2.0));   % learning rate; Gaussian response, pixels
  state = tracker.init(f.rgb, truth);
  box = truth;
  [ground_m_per_px, yaw] = servo_geometry(h, world.cameras(strcmp({world.cameras.name}, 'uav')), uav);

  ious = zeros(frames, 1);
  for k = 1:frames
    t = tic;
    if k > 1
      f = sim4cv_frame(h, 'step');
      [state, box] = tracker.update(state, f.rgb);
    end
    centre = box(1:2) + box(3:4) / 2;
    sim4cv_send_box(h, f.frame_id, box, 1);
    % Visual servo: image x is the UAV's right, image y down is back towards it.
    offset = (centre - [f.width f.height] / 2) .* ground_m_per_px;
    forward = [cos(yaw) sin(yaw)];
    right = [sin(yaw) -cos(yaw)];
    v = servo_gain * (offset(1) * right - offset(2) * forward);
    sim4cv_uav_velocity(h, uav, v(1), v(2), 0);
    truth = target_box(f, target);
    ious(k) = iou(box, truth);
    printf('frame %d: %.1f fps, IoU %.3f\n', f.frame_id, 1 / toc(t), ious(k));
    if show
      imshow(f.rgb); hold on;
      rectangle('Position', box + [0.5 0.5 0 0], 'EdgeColor', 'g');
      if ~isempty(truth), rectangle('Position', truth + [0.5 0.5 0 0], 'EdgeColor', 'r'); end
      hold off; drawnow;
    end
  end
  mean_iou = mean(ious);
  printf('mean IoU %.3f over %d frames\n', mean_iou, frames);
end

% The ground-truth box [x y w h] of entity `id`, or [] if it is not visible.
function box = target_box(f, id)
  box = [];
  b = f.boxes([f.boxes.object_id] == id);
  if ~isempty(b), box = [b.x b.y b.width b.height]; end
end

function v = iou(a, b)
  if isempty(b), v = 0; return; end
  w = max(0, min(a(1) + a(3), b(1) + b(3)) - max(a(1), b(1)));
  h = max(0, min(a(2) + a(4), b(2) + b(4)) - max(a(2), b(2)));
  v = w * h / (a(3) * a(4) + b(3) * b(4) - w * h);
end

% Ground metres per image pixel at the image centre ([along x, along y])
% and the UAV's heading in radians (it keeps it: the servo turns nothing).
function [m_per_px, yaw] = servo_geometry(h, camera, uav)
  s = sim4cv_state(h);
  me = s.entities([s.entities.id] == uav);
  yaw = me.yaw * pi / 180;
  pitch = 60 * pi / 180;                                % the scene's gimbal
  range = me.position(3) / sin(pitch);                  % to the ground along the optical axis
  fy = camera.height / 2 / tan(camera.fov_y_deg * pi / 360);   % focal length, pixels
  m_per_px = [range / fy, range / (fy * sin(pitch))];
end

function finish(h, uav, target)
  try
    sim4cv_uav_follow(h, uav, target);
  catch
  end
  try
    sim4cv_close(h);
  catch
  end
end
