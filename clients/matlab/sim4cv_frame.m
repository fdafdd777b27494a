function f = sim4cv_frame(h, mode, timeout_ms)
% SIM4CV_FRAME  Receive one frame as a struct.
%
%   f = sim4cv_frame(h)                    % 'step'
%   f = sim4cv_frame(h, mode, timeout_ms)
%
%   mode 'step' (default) steps a lockstep subscription and waits for the
%   frame; 'next' waits for the next frame (after sim4cv_step, or with
%   'newest' delivery); 'newest' asks for the newest frame not received yet
%   ('on_request' delivery, on every transport). timeout_ms
%   defaults to 10000; no frame by then is a sim4cv:connection error, as is
%   a daemon that went away.
%
%   f has frame_id, sim_time, camera, render_end_mono_ns (int64,
%   CLOCK_MONOTONIC), width, height, dropped_frames, one field per pixel
%   channel subscribed: rgb (HxWx3 uint8, imshow(f.rgb) shows it upright),
%   depth (HxW single, metres along the optical axis, Inf for sky), mask
%   (HxW uint16 object ids, 0 background), semantic (HxW uint8), normals
%   (HxWx3 single), flow (HxWx2 single), albedo (HxWx3 uint8, the surface
%   colour before any light); boxes (Nx1 struct array with
%   object_id, object_class, x, y, width, height, visibility,
%   visible_pixels; 0x1 if none) and intrinsics (fx, fy, cx, cy; [] without
%   'boxes'). Box x, y are 0-based pixel coordinates as on the wire: the
%   box's top-left pixel is f.rgb(y+1, x+1, :).
%
%   Example:
%     f = sim4cv_frame(h, 'step');
%     b = f.boxes([f.boxes.object_id] == 1);          % the car
%     c = f.mask(b.y + floor(b.height/2) + 1, b.x + floor(b.width/2) + 1);
%
%   See also SIM4CV_SUBSCRIBE, SIM4CV_SEND_BOX.
  if nargin < 2, mode = 'step'; end
  if nargin < 3, timeout_ms = 10000; end
  f = sim4cv_mex('frame', h, mode, timeout_ms);
end
