% A user's Octave session outside the source tree: the sim4cv package (pkg install'ed by
% tests/install/test_install.sh, which defines ADDRESS) gets one frame.
pkg load sim4cv
h = sim4cv_connect(ADDRESS, 'install-test-octave');
sim4cv_subscribe(h, 'uav', {'rgb'}, 'lockstep');
f = sim4cv_frame(h, 'step');
sim4cv_close(h);
assert(isequal(size(f.rgb), [f.height, f.width, 3]) && f.width > 0, 'frame without an RGB image');
printf('frame %d %dx%d rgb_mean %.1f from %s\n', f.frame_id, f.width, f.height, mean(f.rgb(:)), ...
       fileparts(which('sim4cv_connect')));
