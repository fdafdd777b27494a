function result = bench_client_octave(address, frames, warmup)
% BENCH_CLIENT_OCTAVE  Octave client benchmark: lockstep RGB frames over one transport.
%
%   bench_client_octave(address, frames)
%   result = bench_client_octave(address, frames, warmup)
%
%   octave --no-gui --quiet --eval "addpath('clients/matlab', 'build/clients/matlab', 'bench'); \
%       bench_client_octave('shm:///x', 300)"
%
%   Subscribes {'rgb'} in lockstep to the camera 'uav' (over shared memory
%   the ring's camera, 'uav' by default), steps and receives `warmup`
%   (default 10) frames, then `frames` more, and prints one JSON line:
%   {"language":"octave","transport":...,"fps":...,"latency_median_us":...,
%   "latency_p90_us":...,"frames":N}. Latency is render end to frame in hand
%   (f.render_end_mono_ns vs sim4cv_mex('now_ns'), both CLOCK_MONOTONIC),
%   the RGB converted to an HxWx3 uint8 array. It does not start the daemon.
  if nargin < 2, frames = 300; end
  if nargin < 3, warmup = 10; end
  transport = strtok(address, ':');
  h = sim4cv_connect(address, 'bench-octave');
  sim4cv_subscribe(h, 'uav', {'rgb'}, 'lockstep');
  for k = 1:warmup
    sim4cv_frame(h, 'step');
  end
  latencies_us = zeros(frames, 1);
  start = tic;
  for k = 1:frames
    f = sim4cv_frame(h, 'step');
    latencies_us(k) = double(sim4cv_mex('now_ns') - f.render_end_mono_ns) / 1000;
  end
  elapsed = toc(start);
  sim4cv_close(h);
  sorted = sort(latencies_us);
  result = struct('language', 'octave', 'transport', transport, 'fps', round(frames / elapsed * 10) / 10, ...
                  'latency_median_us', round(median(sorted) * 10) / 10, ...
                  'latency_p90_us', round(sorted(floor(0.9 * (frames - 1)) + 1) * 10) / 10, 'frames', frames);
  printf('{"language": "octave", "transport": "%s", "fps": %.1f, "latency_median_us": %.1f, "latency_p90_us": %.1f, "frames": %d}\n', ...
         result.transport, result.fps, result.latency_median_us, result.latency_p90_us, result.frames);
end
