function tracker = mosse(options)
% MOSSE  The MOSSE correlation-filter tracker as a sim4cv Octave tracker.
%
%   tracker = mosse()
%   tracker = mosse(options)
%
%   Returns the struct of function handles of the Octave tracker contract
%   (docs/trax.md, "Octave trackers"):
%
%     state = tracker.init(image, box)            % starts on box in image
%     [state, box] = tracker.update(state, image) % the box in the next image
%
%   image is an HxWx3 uint8 RGB image, box [x y w h] in pixels, 0-based: the
%   top-left corner of the top-left pixel is (0, 0), so the box's top-left
%   pixel is image(y + 1, x + 1, :). The filter is Bolme et al., "Visual
%   Object Tracking using Adaptive Correlation Filters" (CVPR 2010): a
%   Gaussian target response, log + normalisation + cosine window
%   preprocessing, initialised with the first patch and eight random affine
%   warps of it, updated with a learning rate. The search window is twice
%   the box; the box keeps its first size.
%
%   options (a struct, every field optional): eta (learning rate, 0.125),
%   sigma (width of the Gaussian response in pixels, 2).
%
%   As a TraX tracker in sim4cv: octave:clients/matlab/trax/mosse.m
%   In Octave:
%     t = mosse();  s = t.init(rgb0, [x y w h]);  [s, box] = t.update(s, rgb1);
  p = struct('eta', 0.125, 'sigma', 2.0);
  if nargin >= 1
    for f = fieldnames(options)'
      p.(f{1}) = options.(f{1});
    end
  end
  tracker.name = 'mosse';
  tracker.init = @(image, box) mosse_init(image, box, p);
  tracker.update = @mosse_update;
end

function s = mosse_init(image, box, p)
  box = double(box(:)');
  if numel(box) ~= 4 || ~all(box(3:4) > 0)
    error('mosse:badBox', 'mosse: the box must be [x y w h] with a positive size, not %s', mat2str(box));
  end
  s.eta = p.eta;
  s.box_size = [box(4) box(3)];                      % [rows cols]
  s.win = 2 * ceil(s.box_size);                      % search window, twice the object
  s.centre = box(1:2) + box(3:4) / 2;                % [x y], continuous pixels
  s.G = fft2(gaussian_response(s.win, p.sigma));
  s.cosine = hann_window(s.win(1)) * hann_window(s.win(2))';
  [s.A, s.B] = initial_filter(crop(gray(image), s.centre, s.win), s.G, s.cosine);
  s.lambda = 0.01 * mean(s.B(:));                    % regularisation: no division by ~0
end

function [s, box] = mosse_update(s, image)
  image = gray(image);
  F = fft2(preprocess(crop(image, s.centre, s.win), s.cosine));
  response = real(ifft2((s.A ./ (s.B + s.lambda)) .* F));
  [~, peak] = max(response(:));
  [row, col] = ind2sub(s.win, peak);
  s.centre = s.centre + [col row] - (floor(s.win([2 1]) / 2) + 1);   % the peak moves with the object
  F = fft2(preprocess(crop(image, s.centre, s.win), s.cosine));
  s.A = s.eta * s.G .* conj(F) + (1 - s.eta) * s.A;
  s.B = s.eta * F .* conj(F) + (1 - s.eta) * s.B;
  box = [s.centre - s.box_size([2 1]) / 2, s.box_size([2 1])];
end

function g = gray(rgb)
  g = 0.299 * double(rgb(:, :, 1)) + 0.587 * double(rgb(:, :, 2)) + 0.114 * double(rgb(:, :, 3));
end

% The win-sized patch centred on `centre` ([x y], continuous pixel
% coordinates, origin at the image's top-left corner), edges replicated.
function patch = crop(image, centre, win)
  rows = round(centre(2) - 0.5) - floor(win(1) / 2) + (1:win(1));
  cols = round(centre(1) - 0.5) - floor(win(2) / 2) + (1:win(2));
  rows = min(max(rows, 1), size(image, 1));
  cols = min(max(cols, 1), size(image, 2));
  patch = image(rows, cols);
end

% Log, zero mean and unit norm, then the cosine window (Bolme et al. 3.1).
function x = preprocess(patch, cosine)
  x = log(patch + 1);
  x = (x - mean(x(:))) / (std(x(:)) + 1e-5);
  x = x .* cosine;
end

function w = hann_window(n)
  w = 0.5 * (1 - cos(2 * pi * (0:n - 1)' / (n - 1)));
end

function g = gaussian_response(win, sigma)
  [c, r] = meshgrid(1:win(2), 1:win(1));
  centre = floor(win / 2) + 1;
  g = exp(-((r - centre(1)) .^ 2 + (c - centre(2)) .^ 2) / (2 * sigma ^ 2));
end

% The filter's numerator and denominator from the first patch and eight
% random small affine warps of it (rotation, scale, shear).
function [A, B] = initial_filter(patch, G, cosine)
  rand('seed', 1);
  F = fft2(preprocess(patch, cosine));
  A = G .* conj(F);
  B = F .* conj(F);
  [rows, cols] = size(patch);
  [c, r] = meshgrid(1:cols, 1:rows);
  c0 = (cols + 1) / 2; r0 = (rows + 1) / 2;
  for k = 1:8
    angle = (rand - 0.5) * pi / 8;
    M = [cos(angle) -sin(angle); sin(angle) cos(angle)] * (eye(2) + (rand(2) - 0.5) * 0.1);
    source = M \ [c(:)' - c0; r(:)' - r0];
    warped = interp2(c, r, patch, source(1, :) + c0, source(2, :) + r0, 'linear', mean(patch(:)));
    F = fft2(preprocess(reshape(warped, rows, cols), cosine));
    A = A + G .* conj(F);
    B = B + F .* conj(F);
  end
  A = A / 9;   % the mean over the samples, the scale of one update
  B = B / 9;
end
