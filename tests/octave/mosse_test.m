function mosse_test(address, frames)
% MOSSE_TEST  The MOSSE example (clients/matlab/examples/mosse_tracker.m)
% flies the UAV in the loop for `frames` frames (default 60) at `address`
% (shared memory in tests/octave/run.sh) and must keep a mean IoU with the
% car's ground-truth box above 0.5.
  if nargin < 2, frames = 60; end
  iou = mosse_tracker(address, frames);
  if ~(iou > 0.5)
    error('mosse_test:failed', 'mean IoU %.3f over %d frames, not above 0.5', iou, frames);
  end
  printf('mosse_test: mean IoU %.3f over %d frames passed\n', iou, frames);
  % The tracker loop docs/clients.md shows runs as written.
  box = ssd_tracker_loop(address, 30);
  if ~(numel(box) == 4 && all(box(3:4) > 0))
    error('mosse_test:failed', 'ssd_tracker_loop ended with box %s', mat2str(box));
  end
  printf('ssd_tracker_loop: 30 frames, last box %s\n', mat2str(box));
end
