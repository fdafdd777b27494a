function sim4cv_send_box(h, frame_id, box, confidence)
% SIM4CV_SEND_BOX  Report a tracker's box for a frame it processed.
%
%   sim4cv_send_box(h, frame_id, [x y w h])
%   sim4cv_send_box(h, frame_id, [x y w h], confidence)
%
%   The box is in pixels with the origin at the image's top-left corner,
%   as the frame's boxes are (0-based); confidence in [0, 1] (default 1).
%   The next sim4cv_state after the simulation applied it shows it in
%   last_tracker_output (docs/protocol.md, TrackerOutput).
%
%   Example:
%     f = sim4cv_frame(h, 'step');
%     sim4cv_send_box(h, f.frame_id, [150 70 20 36], 0.9);
  if nargin < 4, confidence = 1; end
  sim4cv_mex('send_box', h, frame_id, double(box), confidence);
end
