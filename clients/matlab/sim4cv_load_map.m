function world = sim4cv_load_map(h, name)
% SIM4CV_LOAD_MAP  Replace the world with a shipped tile map; returns the new world.
%
%   world = sim4cv_load_map(h, name)
%
%   name is relative to the daemon's maps folder without '.map', e.g.
%   'tracking/hard_urban' or 'driving/test/01_desert' (docs/maps.md). The
%   map's car (id 1) drives its first route, its UAV (id 2) films it.
%   world is as sim4cv_world returns it.
%
%   Example:
%     w = sim4cv_load_map(h, 'tracking/hard_urban');
%
%   See also SIM4CV_WORLD.
  world = sim4cv_mex('load_map', h, name);
end
