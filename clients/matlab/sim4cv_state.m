function s = sim4cv_state(h)
% SIM4CV_STATE  Poses of every entity now.
%
%   s = sim4cv_state(h)
%
%   s has frame_id, sim_time and entities, an Nx1 struct array with id,
%   name, kind ('car', 'uav', 'pedestrian'), position [x y z] (metres,
%   x east, y north, z up), yaw (degrees counter-clockwise from east),
%   orientation [w x y z] (body -> world) and velocity [vx vy vz] (m/s);
%   last_tracker_output (frame_id, box [x y w h], confidence): the last box
%   this connection sent with sim4cv_send_box that the simulation applied.
%
%   Example:
%     s = sim4cv_state(h);
%     car = s.entities(strcmp({s.entities.name}, 'car'));
%     disp(car.position);
  s = sim4cv_mex('state', h);
end
