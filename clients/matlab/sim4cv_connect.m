function h = sim4cv_connect(address, name, timeout_ms, protocol_version)
% SIM4CV_CONNECT  Connect to sim4cvd; returns a handle for the other sim4cv_* functions.
%
%   h = sim4cv_connect(address)
%   h = sim4cv_connect(address, name, timeout_ms, protocol_version)
%
%   address is 'tcp://HOST:PORT', 'udp://HOST:PORT' or 'shm:///NAME' (NAME
%   as given to sim4cvd --shm-name). name (default 'octave-client') shows in
%   the daemon's log. timeout_ms (default 5000) covers connecting and the
%   handshake; protocol_version 0 (default) is this build's.
%
%   Errors: sim4cv:badArgument (an address of another form),
%   sim4cv:connection (nothing answers there within the timeout),
%   sim4cv:server (the daemon refused, e.g. ERROR_CODE_VERSION_MISMATCH).
%
%   Example:
%     h = sim4cv_connect('tcp://127.0.0.1:5555', 'my-tracker');
%     sim4cv_subscribe(h, 'uav', {'rgb', 'boxes'}, 'lockstep');
%     f = sim4cv_frame(h, 'step');
%     sim4cv_close(h);
%
%   See also SIM4CV_CLOSE, SIM4CV_SUBSCRIBE, SIM4CV_FRAME.
  if nargin < 2, name = 'octave-client'; end
  if nargin < 3, timeout_ms = 5000; end
  if nargin < 4, protocol_version = 0; end
  h = sim4cv_mex('connect', address, name, timeout_ms, protocol_version);
end
