function client_test(tcp, udp, shm, daemon_pid)
% CLIENT_TEST  The Octave client against a running sim4cvd (tests/octave/run.sh).
%
%   client_test('tcp://127.0.0.1:P', 'udp://127.0.0.1:Q', 'shm:///NAME', pid)
%
%   The daemon runs with --mode lockstep --shm-channels rgb,depth,mask; it is
%   killed (SIGKILL) at the end, so start a fresh one for anything after.
%   Every failed check is an error().
  names = {'tcp', 'udp', 'shm'};
  addresses = {tcp, udp, shm};
  for i = 1:3
    t = tic;
    check_transport(names{i}, addresses{i}, i);
    printf('client_test: %s passed (%.1f s)\n', names{i}, toc(t));
  end
  t = tic;
  check_bad_input(tcp, udp, shm);
  printf('client_test: bad input passed (%.1f s)\n', toc(t));
  t = tic;
  check_long_responses(tcp, shm);
  printf('client_test: long responses over shared memory passed (%.1f s)\n', toc(t));
  t = tic;
  check_daemon_killed(tcp, udp, shm, daemon_pid);
  printf('client_test: daemon killed mid-session passed (%.1f s)\n', toc(t));
  printf('client_test: all passed\n');
end

function check(condition, varargin)
  if ~condition
    error('client_test:failed', varargin{:});
  end
end

function check_transport(name, address, index)
  h = sim4cv_connect(address, ['octave-test-' name]);
  sim4cv_subscribe(h, 'uav', {'rgb', 'depth', 'mask', 'boxes'}, 'lockstep');
  last = 0;
  for k = 1:5
    t = tic;
    f = sim4cv_frame(h, 'step');
    check(toc(t) < 2, '%s: frame %d took %.1f s', name, k, toc(t));
    check(f.frame_id > last, '%s: frame_id %d after %d', name, f.frame_id, last);
    last = f.frame_id;
    check(isa(f.rgb, 'uint8') && isequal(size(f.rgb), [180 320 3]), '%s: rgb is %s %s', name, class(f.rgb), mat2str(size(f.rgb)));
    check(isa(f.depth, 'single') && isequal(size(f.depth), [180 320]), '%s: depth is %s %s', name, class(f.depth), mat2str(size(f.depth)));
    check(isa(f.mask, 'uint16') && isequal(size(f.mask), [180 320]), '%s: mask is %s %s', name, class(f.mask), mat2str(size(f.mask)));
    check(isa(f.render_end_mono_ns, 'int64') && f.render_end_mono_ns > 0, '%s: render_end_mono_ns', name);
    check(f.width == 320 && f.height == 180 && strcmp(f.camera, 'uav'), '%s: frame size or camera', name);
  end
  check_pixels(name, f);
  sim4cv_step(h);
  g = sim4cv_frame(h, 'next', 5000);
  check(g.frame_id > last, '%s: step + next gave frame %d after %d', name, g.frame_id, last);

  % send_box: the simulation applies it with a following frame; the State
  % after that carries it (over shm the request ring may deliver it a frame later).
  sim4cv_send_box(h, last, [10 20 30 40], 0.5);
  for k = 1:3
    sim4cv_frame(h, 'step');
    s = sim4cv_state(h);
    if s.last_tracker_output.frame_id == last, break; end
  end
  check(s.last_tracker_output.frame_id == last, '%s: last_tracker_output.frame_id %d, not %d', name, s.last_tracker_output.frame_id, last);
  check(isequal(s.last_tracker_output.box, [10 20 30 40]), '%s: last_tracker_output.box %s', name, mat2str(s.last_tracker_output.box));
  car = s.entities(strcmp({s.entities.name}, 'car'));
  check(numel(car) == 1 && car.id == 1 && strcmp(car.kind, 'car') && numel(car.position) == 3, '%s: the car in State', name);

  % Each transport drives a car of its own: a car takes Controls from one
  % client at a time, and a UDP client that stops (there is no goodbye)
  % keeps its car until its registration lapses or its Controls time out.
  car_id = sim4cv_spawn(h, 'car', sprintf('octave_car_%s', name), 10 * index - 20, -25, 0);
  sim4cv_controls(h, car_id, 0, 0, 1);   % brake it (no error expected)
  sim4cv_frame(h, 'step');

  uav_name = sprintf('octave_uav_%s', name);
  id = sim4cv_spawn(h, 'uav', uav_name, 5 * index, 5, 20);
  check(isnumeric(id) && isscalar(id) && id > 2, '%s: spawn returned %s', name, mat2str(id));
  w = sim4cv_world(h);
  check(sum([w.entities.id] == id) == 1 && sum(strcmp({w.entities.name}, uav_name)) == 1, '%s: the world lists uav %d %d times', name, id, sum([w.entities.id] == id));
  check(any(strcmp({w.cameras.name}, 'uav')), '%s: the world has no camera uav', name);
  w = sim4cv_uav_velocity(h, id, 1, 0, 0);
  check(strcmp(w.entities([w.entities.id] == id).kind, 'uav'), '%s: uav_velocity world', name);
  cam = ['octave_cam_' name];
  w = sim4cv_add_camera(h, struct('name', cam, 'mounted_on', uav_name, 'width', 64, 'height', 48, ...
                                  'fov_y_deg', 60, 'pitch_down_deg', 45, 'gimbal', true));
  added = w.cameras(strcmp({w.cameras.name}, cam));
  check(numel(added) == 1 && added.width == 64 && added.height == 48 && strcmp(added.mounted_on, uav_name), '%s: add_camera', name);
  sim4cv_uav_follow(h, id, 1);
  % Over UDP (no goodbye) close releases the lockstep subscription first,
  % or the next transport's first frame would wait for the registration to
  % lapse (and the shm client be expired meanwhile).
  sim4cv_close(h);
  expect_error(@() sim4cv_frame(h, 'step'), 'sim4cv:badHandle', 'is not an open sim4cv connection (closed, or never opened)');
end

% The pixels are where the boxes say: the tight box of a box's object id in
% the mask is the box exactly, the mask at its centre is its id, the car's
% pixels are red in rgb (channel order) and nearer than the road around it.
function check_pixels(name, f)
  check(numel(f.boxes) >= 1 && size(f.boxes, 2) == 1, '%s: %d boxes', name, numel(f.boxes));
  fields = {'object_id', 'object_class', 'x', 'y', 'width', 'height', 'visibility'};
  for k = 1:numel(fields)
    check(isfield(f.boxes, fields{k}), '%s: boxes lack field %s', name, fields{k});
  end
  for b = f.boxes'
    in = f.mask == b.object_id;
    rows = find(any(in, 2));
    cols = find(any(in, 1));
    check(~isempty(rows) && rows(1) - 1 == b.y && rows(end) == b.y + b.height && cols(1) - 1 == b.x && cols(end) == b.x + b.width, ...
          '%s: object %d: mask spans rows %d..%d cols %d..%d, box [%d %d %d %d]', name, b.object_id, rows(1), rows(end), cols(1), cols(end), b.x, b.y, b.width, b.height);
    check(nnz(in) == b.visible_pixels, '%s: object %d has %d mask pixels, box says %d', name, b.object_id, nnz(in), b.visible_pixels);
  end
  car = f.boxes([f.boxes.object_id] == 1);
  check(numel(car) == 1 && strcmp(car.object_class, 'car'), '%s: no car box', name);
  cy = car.y + floor(car.height / 2) + 1;
  cx = car.x + floor(car.width / 2) + 1;
  check(f.mask(cy, cx) == 1, '%s: mask at the car box centre is %d', name, f.mask(cy, cx));
  in = f.mask == 1;
  rgb = double(reshape(f.rgb, [], 3));
  car_colour = mean(rgb(in(:), :), 1);
  check(car_colour(1) > car_colour(2) + 40 && car_colour(1) > car_colour(3) + 40, '%s: the car is not red: %s', name, mat2str(car_colour, 3));
  ring = false(size(in));
  ring(max(car.y - 4, 0) + 1:min(car.y + car.height + 4, 180), max(car.x - 4, 0) + 1:min(car.x + car.width + 4, 320)) = true;
  ring = ring & f.mask == 0;
  check(median(f.depth(in)) < median(f.depth(ring)), '%s: the car (%.2f m) is not nearer than the road around it (%.2f m)', name, median(f.depth(in)), median(f.depth(ring)));
  % Row-major bytes of the wire reinterpreted: pixel (row r, column c) of
  % rgb is bytes 3*(r*320+c) .. +2; permuting back gives that order.
  bytes = reshape(permute(f.rgb, [3 2 1]), 1, []);
  r = cy - 1; c = cx - 1;
  check(isequal(bytes(3 * (r * 320 + c) + (1:3)), reshape(f.rgb(cy, cx, :), 1, 3)), '%s: byte order', name);
end

function expect_error(fn, identifier, text)
  try
    fn();
  catch e
    check(strcmp(e.identifier, identifier), 'expected %s, got %s: %s', identifier, e.identifier, e.message);
    check(isempty(text) || ~isempty(strfind(e.message, text)), 'error %s says "%s", not "%s"', identifier, e.message, text);
    return;
  end
  error('client_test:failed', 'expected a %s error, got none', identifier);
end

function check_bad_input(tcp, udp, shm)
  h = sim4cv_connect(tcp, 'octave-bad');
  sim4cv_close(h);
  msg = 'is not an open sim4cv connection (closed, or never opened)';
  expect_error(@() sim4cv_frame(h, 'step'), 'sim4cv:badHandle', msg);
  expect_error(@() sim4cv_close(h), 'sim4cv:badHandle', msg);
  expect_error(@() sim4cv_state(12345), 'sim4cv:badHandle', msg);
  expect_error(@() sim4cv_step('abc'), 'sim4cv:badHandle', msg);
  expect_error(@() sim4cv_world([1 2]), 'sim4cv:badHandle', msg);
  expect_error(@() sim4cv_connect('foo://nowhere:1'), 'sim4cv:badArgument', 'foo://nowhere:1');
  expect_error(@() sim4cv_connect('tcp://127.0.0.1'), 'sim4cv:badArgument', 'tcp://127.0.0.1');
  expect_error(@() sim4cv_mex('subscribe', 1), 'sim4cv:badArgument', 'subscribe');
  expect_error(@() sim4cv_mex('no_such_command'), 'sim4cv:badArgument', 'no_such_command');

  h = sim4cv_connect(tcp, 'octave-bad-args');
  expect_error(@() sim4cv_subscribe(h, 'uav', {'rgb', 'colour'}, 'lockstep'), 'sim4cv:badArgument', 'colour');
  expect_error(@() sim4cv_subscribe(h, 'uav', {'rgb'}, 'sometimes'), 'sim4cv:badArgument', 'sometimes');
  expect_error(@() sim4cv_subscribe(h, 'no_camera', {'rgb'}, 'lockstep'), 'sim4cv:server', 'ERROR_CODE_UNKNOWN_CAMERA');
  expect_error(@() sim4cv_send_box(h, 1, [1 2 3]), 'sim4cv:badArgument', 'send_box');
  expect_error(@() sim4cv_spawn(h, 'boat', 'b', 0, 0, 0), 'sim4cv:badArgument', 'boat');
  expect_error(@() sim4cv_uav_velocity(h, 99, 1, 0, 0), 'sim4cv:server', 'ERROR_CODE_UNKNOWN_ENTITY');
  expect_error(@() sim4cv_add_camera(h, struct('name', 'c', 'colour', 1)), 'sim4cv:badArgument', 'colour');
  sim4cv_close(h);

  % Nothing there: refused (tcp), unanswered (udp), not served (shm), each within its timeout.
  nobody = {'tcp://127.0.0.1:1', 'udp://127.0.0.1:1', sprintf('shm:///sim4cv-octave-nobody-%d', getpid())};
  for k = 1:numel(nobody)
    t = tic;
    expect_error(@() sim4cv_connect(nobody{k}, 'octave-nobody', 1000), 'sim4cv:connection', '');
    check(toc(t) < 3, '%s: the connection error took %.1f s with a 1 s timeout', nobody{k}, toc(t));
  end

  addresses = {tcp, udp, shm};
  for k = 1:3
    expect_error(@() sim4cv_connect(addresses{k}, 'octave-v99', 5000, 99), 'sim4cv:server', 'ERROR_CODE_VERSION_MISMATCH');
  end
end

% 40 entities with 63-character names make the Welcome and the State longer
% than a shared-memory response message: they come over the attachment's
% socket, whole.
function check_long_responses(tcp, shm)
  h = sim4cv_connect(tcp, 'octave-spawner');
  names = cell(1, 40);
  for k = 1:40
    names{k} = sprintf('%-63s', sprintf('octave-uav-with-a-name-as-long-as-allowed-%02d', k));
    names{k}(names{k} == ' ') = 'x';
    sim4cv_spawn(h, 'uav', names{k}, -100 + 6 * mod(k, 20), 60 + 6 * floor(k / 20), 25);
  end
  sim4cv_subscribe(h, 'uav', {'boxes'}, 'lockstep');
  sim4cv_frame(h, 'step');   % the published State lists them
  sim4cv_close(h);
  for attempt = 1:2
    hs = sim4cv_connect(shm, sprintf('octave-long-%d', attempt));
    s = sim4cv_state(hs);
    missing = setdiff(names, {s.entities.name});
    check(isempty(missing), 'attachment %d: the State over shared memory lacks %d names, e.g. %s', attempt, numel(missing), strjoin(missing(1:min(end, 1)), ''));
    sim4cv_close(hs);
  end
end

function check_daemon_killed(tcp, udp, shm, pid)
  ht = sim4cv_connect(tcp, 'octave-kill-tcp');
  hu = sim4cv_connect(udp, 'octave-kill-udp');
  hs = sim4cv_connect(shm, 'octave-kill-shm');
  sim4cv_subscribe(ht, 'uav', {'rgb'}, 'lockstep');
  sim4cv_subscribe(hu, 'uav', {'rgb'}, 'on_request');    % neither holds lockstep back
  sim4cv_subscribe(hs, 'uav', {'rgb'}, 'on_request');
  sim4cv_frame(ht, 'step');
  sim4cv_frame(hu, 'newest');
  sim4cv_frame(hs, 'newest');
  kill(pid, 9);
  handles = {ht, hu, hs};
  modes = {'step', 'newest', 'newest'};
  for k = 1:3
    t = tic;
    try
      sim4cv_frame(handles{k}, modes{k}, 2000);
      sim4cv_frame(handles{k}, modes{k}, 2000);   % one frame may still have been on its way
      error('client_test:failed', 'frame %s after the daemon was killed gave no error', modes{k});
    catch e
      check(strncmp(e.identifier, 'sim4cv:', 7), 'after the kill: %s: %s', e.identifier, e.message);
    end
    check(toc(t) < 5, 'the error after the kill took %.1f s', toc(t));
    sim4cv_close(handles{k});
  end
end
