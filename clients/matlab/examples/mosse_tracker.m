function mean_iou = mosse_tracker(address, frames, show)
% MOSSE_TRACKER  A MOSSE correlation-filter tracker flying a UAV in the loop.
%
%   mean_iou = mosse_tracker(address, frames)
%   mean_iou = mosse_tracker(address, frames, show)
%
%   Connects to sim4cvd at address (e.g. 'shm:///sim4cv', 'tcp://127.0.0.1:5555'),
%   subscribes to the camera 'uav' in lockstep and tracks the car the UAV
%   films: the filter (Bolme et al., "Visual Object Tracking using Adaptive
%   Correlation Filters", CVPR 2010) starts from the first frame's
%   ground-truth box of the car. Each frame it sends its box
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
  eta = 0.125;          % learning rate
  sigma = 2.0;          % Gaussian target response, pixels
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
  box_size = [truth(4) truth(3)];                    % [rows cols]
  win = 2 * ceil(box_size);                          % search window, twice the object
  centre = truth(1:2) + truth(3:4) / 2;              % [x y], continuous pixels
  G = fft2(gaussian_response(win, sigma));
  cosine = hann_window(win(1)) * hann_window(win(2))';
  [A, B] = initial_filter(crop(gray(f.rgb), centre, win), G, cosine);
  lambda = 0.01 * mean(B(:));                        % regularisation: no division by ~0
  [ground_m_per_px, yaw] = servo_geometry(h, world.cameras(strcmp({world.cameras.name}, 'uav')), uav);

  ious = zeros(frames, 1);
  for k = 1:frames
    t = tic;
    if k > 1
      f = sim4cv_frame(h, 'step');
      image = gray(f.rgb);
      F = fft2(preprocess(crop(image, centre, win), cosine));
      response = real(ifft2((A ./ (B + lambda)) .* F));
      [~, peak] = max(response(:));
      [row, col] = ind2sub(win, peak);
      centre = centre + [col row] - (floor(win([2 1]) / 2) + 1);   % the peak moves with the object
      F = fft2(preprocess(crop(image, centre, win), cosine));
      A = eta * G .* conj(F) + (1 - eta) * A;
      B = eta * F .* conj(F) + (1 - eta) * B;
    end
    box = [centre - box_size([2 1]) / 2, box_size([2 1])];
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

function g = gray(rgb)
  g = 0.299 * double(rgb(:, :, 1)) + 0.587 * double(rgb(:, :, 2)) + 0.114 * double(rgb(:, :, 3));
end

% The win-sized patch centred on `centre` ([x y], continuous pixel
% coordinates, origin at the image's top-left corner), edges replicated.
function patch = crop(image, centre, win)
  rows = round(centre(2) - 0.5) - floor(win(1) / 2) + (1:win(1));
  cols = round(centre(1) - 0.5) - floor(win(2) / 2) + (1:win(2));
  rows = min(max(rows, 1), size(image, 1));
  cols = min(max(cols, 1), size(image, 2));
  patch = image(rows, cols);
end

% Log, zero mean and unit norm, then the cosine window (Bolme et al. 3.1).
function x = preprocess(patch, cosine)
  x = log(patch + 1);
  x = (x - mean(x(:))) / (std(x(:)) + 1e-5);
  x = x .* cosine;
end

function w = hann_window(n)
  w = 0.5 * (1 - cos(2 * pi * (0:n - 1)' / (n - 1)));
end

function g = gaussian_response(win, sigma)
  [c, r] = meshgrid(1:win(2), 1:win(1));
  centre = floor(win / 2) + 1;
  g = exp(-((r - centre(1)) .^ 2 + (c - centre(2)) .^ 2) / (2 * sigma ^ 2));
end

% The filter's numerator and denominator from the first patch and eight
% random small affine warps of it (rotation, scale, shear).
function [A, B] = initial_filter(patch, G, cosine)
  rand('seed', 1);
  F = fft2(preprocess(patch, cosine));
  A = G .* conj(F);
  B = F .* conj(F);
  [rows, cols] = size(patch);
  [c, r] = meshgrid(1:cols, 1:rows);
  c0 = (cols + 1) / 2; r0 = (rows + 1) / 2;
  for k = 1:8
    angle = (rand - 0.5) * pi / 8;
    M = [cos(angle) -sin(angle); sin(angle) cos(angle)] * (eye(2) + (rand(2) - 0.5) * 0.1);
    source = M \ [c(:)' - c0; r(:)' - r0];
    warped = interp2(c, r, patch, source(1, :) + c0, source(2, :) + r0, 'linear', mean(patch(:)));
    F = fft2(preprocess(reshape(warped, rows, cols), cosine));
    A = A + G .* conj(F);
    B = B + F .* conj(F);
  end
  A = A / 9;   % the mean over the samples, the scale of one update
  B = B / 9;
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
