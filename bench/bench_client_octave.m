function result = bench_client_octave(address, frames, age, period_ms)
% BENCH_CLIENT_OCTAVE  The Octave client's part of the client benchmark.
%
%   bench_client_octave(address, frames)
%   bench_client_octave(address, frames, true [, period_ms])
%
%   octave --no-gui --quiet --eval "addpath('clients/matlab', 'build/clients/matlab', 'bench'); \
%       bench_client_octave('shm:///x', 300)"
%
%   Without age: subscribes {'rgb'} in lockstep to the camera 'uav' (over
%   shared memory the ring's camera, 'uav' by default), steps and receives 10
%   frames, then `frames` more, and prints one JSON line:
%   {"language":"octave","transport":...,"fps":...,"latency_median_us":...,
%   "latency_p90_us":...,"frames":N}. Latency is render end to frame in hand
%   (f.render_end_mono_ns vs sim4cv_mex('now_ns'), both CLOCK_MONOTONIC),
%   the RGB converted to an HxWx3 uint8 array.
%   With age true (a realtime daemon): asks for the newest frame every
%   period_ms (default 100) milliseconds, `frames` times, and prints the
%   frames' age in hand: age_median_ms, age_p90_ms, age_max_ms.
%   bench/bench_clients.py runs it beside the C++ and Python clients. It
%   does not start the daemon.
  if nargin < 2, frames = 300; end
  if nargin < 3, age = false; end
  if nargin < 4, period_ms = 100; end
  transport = strtok(address, ':');
  h = sim4cv_connect(address, 'bench-octave');
  if age
    sim4cv_subscribe(h, 'uav', {'rgb'}, 'on_request');
    ages_ms = zeros(frames, 1);
    for k = 1:frames
      pause(period_ms / 1000);
      f = sim4cv_frame(h, 'newest');
      ages_ms(k) = double(sim4cv_mex('now_ns') - f.render_end_mono_ns) / 1e6;
    end
    sim4cv_close(h);
    sorted = sort(ages_ms);
    result = struct('language', 'octave', 'transport', transport, 'period_ms', period_ms, ...
                    'age_median_ms', median(sorted), 'age_p90_ms', sorted(floor(0.9 * (frames - 1)) + 1), ...
                    'age_max_ms', sorted(end), 'frames', frames);
    printf('{"language": "octave", "transport": "%s", "period_ms": %d, "age_median_ms": %.1f, "age_p90_ms": %.1f, "age_max_ms": %.1f, "frames": %d}\n', ...
           transport, period_ms, result.age_median_ms, result.age_p90_ms, result.age_max_ms, frames);
    return;
  end
  sim4cv_subscribe(h, 'uav', {'rgb'}, 'lockstep');
  for k = 1:10
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
  result = struct('language', 'octave', 'transport', transport, 'fps', frames / elapsed, ...
                  'latency_median_us', median(sorted), 'latency_p90_us', sorted(floor(0.9 * (frames - 1)) + 1), ...
                  'frames', frames);
  printf('{"language": "octave", "transport": "%s", "fps": %.1f, "latency_median_us": %.1f, "latency_p90_us": %.1f, "frames": %d}\n', ...
         transport, result.fps, result.latency_median_us, result.latency_p90_us, frames);
end
