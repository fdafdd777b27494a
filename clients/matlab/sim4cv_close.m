function sim4cv_close(h)
% SIM4CV_CLOSE  Close a connection opened by sim4cv_connect.
%
%   sim4cv_close(h)
%
%   The handle is invalid afterwards: using it again gives a
%   sim4cv:badHandle error. Every open connection is also closed when the
%   MEX file is cleared ('clear sim4cv_mex' or 'clear all').
%
%   Example:
%     h = sim4cv_connect('shm:///sim4cv');
%     sim4cv_close(h);
  sim4cv_mex('close', h);
end
