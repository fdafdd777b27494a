function sim4cv_step(h)
% SIM4CV_STEP  Lockstep: ask for the next frame without waiting for it.
%
%   sim4cv_step(h)
%
%   Receive the frame with sim4cv_frame(h, 'next'). sim4cv_frame(h, 'step')
%   does both in one call.
%
%   Example:
%     sim4cv_step(h);
%     f = sim4cv_frame(h, 'next');
%
%   See also SIM4CV_FRAME.
  sim4cv_mex('step', h);
end
