function sim4cv_trax_server(file)
% SIM4CV_TRAX_SERVER  Runs a tracker written in Octave as a TraX server.
%
%   sim4cv_trax_server('path/to/NAME.m')
%
%   Speaks TraX (protocol version 1; docs/trax.md) on Octave's standard
%   input and output, for sim4cv's tracker specification octave:NAME.m,
%   which sim4cv (clients/python/sim4cv/trax.py) runs as
%
%     octave --no-gui --no-window-system --quiet --no-history --eval ...
%       "addpath('REPO/clients/matlab/trax'); sim4cv_trax_server('/abs/NAME.m')"
%
%   NAME.m defines the tracker as a function with no arguments returning a
%   struct of function handles (the contract; mosse.m here is one):
%
%     tracker = NAME()
%     state = tracker.init(image, box)
%     [state, box] = tracker.update(state, image)
%     tracker.name (optional): the trax.name announced (default NAME)
%
%   image: HxWx3 uint8 RGB. box: [x y w h] in pixels, 0-based (the top-left
%   corner of the top-left pixel is (0, 0); the box's top-left pixel is
%   image(y + 1, x + 1, :)). update may return [] or a box with a NaN for
%   "no estimate in this frame". state is whatever init returns.
%
%   Announces rectangle regions and memory images (raw RGB in Base64,
%   decoded with matlab.net.base64decode) and path images (imread). Each
%   state message carries octave.time: the seconds the tracker's own init or
%   update took. Whatever the tracker prints (disp, printf, fprintf(1, ...))
%   is captured with evalc and copied to stderr, so that only TraX lines
%   reach stdout. An error in the tracker, a bad contract, or a message the
%   server cannot serve ends the session with
%     @@TRAX:quit "trax.reason=..."
%   naming the error (its message, function and line), and Octave exits with
%   status 1. It exits with status 0 on quit or at the end of its input.
  more off;
  page_screen_output(false);
  status = 0;
  try
    status = serve(file);
  catch err
    send_quit(['sim4cv_trax_server: ' describe(err)]);
    status = 1;
  end
  exit(status);
end

function status = serve(file)
  try
    [tracker, name] = load_tracker(file);
  catch err
    send_quit(err.message);                  % it names the file, and the tracker's error where it is one
    status = 1;
    return;
  end
  memory = has_base64();
  formats = 'path;';
  if memory
    formats = 'memory;path;';
  end
  send(['@@TRAX:hello "trax.version=1" "trax.name=' escape(name) '" "trax.region=rectangle;" "trax.image=' ...
        formats '"']);
  state = [];
  initialized = false;
  while true
    [msg, ended] = read_message();
    if ended
      status = 0;
      return;
    end
    switch msg.name
      case 'quit'
        status = 0;
        return;
      case 'initialize'
        if numel(msg.args) ~= 2
          status = protocol_error(sprintf('initialize has %d arguments, not 2 (an image and a region)', ...
                                          numel(msg.args)));
          return;
        end
        try
          image = decode_image(msg.args{1}, msg.payload);
          box = parse_region(msg.args{2});
        catch err
          status = protocol_error(['cannot read initialize: ' err.message]);
          return;
        end
        try
          t = tic;
          output = evalc('state = tracker.init(image, box);');
          seconds = toc(t);
        catch err
          forward(err);
          status = tracker_error(name, 'init', err);
          return;
        end
        forward(output);
        initialized = true;
        send_state(box, seconds);
      case 'frame'
        if ~initialized
          status = protocol_error('frame before initialize');
          return;
        end
        if numel(msg.args) ~= 1
          status = protocol_error(sprintf('frame has %d arguments, not 1 (an image)', numel(msg.args)));
          return;
        end
        try
          image = decode_image(msg.args{1}, msg.payload);
        catch err
          status = protocol_error(['cannot read the frame: ' err.message]);
          return;
        end
        try
          t = tic;
          output = evalc('[state, box] = tracker.update(state, image);');
          seconds = toc(t);
        catch err
          forward(err);
          status = tracker_error(name, 'update', err);
          return;
        end
        forward(output);
        if ~(isempty(box) || (isnumeric(box) && isreal(box) && numel(box) == 4))
          send_quit(sprintf('%s: update returned a %s %s, not a box [x y w h] or []', name, ...
                            mat2str(size(box)), class(box)));
          status = 1;
          return;
        end
        send_state(box, seconds);
      otherwise                            % hello, state: a client does not send them
        status = protocol_error(sprintf('unexpected message %s', msg.name));
        return;
    end
  end
end

% The tracker struct of NAME.m, and its trax.name.
function [tracker, name] = load_tracker(file)
  if ~ischar(file) || isempty(file)
    error('sim4cv_trax_server needs the file of the tracker, e.g. sim4cv_trax_server(''mosse.m'')');
  end
  path = make_absolute_filename(file);
  [folder, name, ext] = fileparts(path);
  if ~strcmp(ext, '.m')
    error('the Octave tracker %s is not a .m file', path);
  end
  if ~isfile(path)
    error('the Octave tracker file %s does not exist', path);
  end
  if ~isvarname(name)
    error('the Octave tracker file %s: %s is not a valid function name', path, name);
  end
  addpath(folder);
  found = which(name);
  if ~strcmp(found, path) && ~strcmp(canonicalize_file_name(found), canonicalize_file_name(path))
    error('the Octave tracker %s is shadowed by %s of the same name', path, found);
  end
  try                                          % in the base workspace: feval here would find
    output = evalc('tracker = evalin(''base'', [name ''();'']);');   % this file's own send, serve, ...
  catch err
    forward(err);
    error('%s() failed: %s', name, describe(err));
  end
  forward(output);
  if ~(isstruct(tracker) && isscalar(tracker) && isfield(tracker, 'init') && isfield(tracker, 'update') ...
       && is_function_handle(tracker.init) && is_function_handle(tracker.update))
    error(['%s() must return a struct with the function handles init (state = init(image, box)) ' ...
           'and update ([state, box] = update(state, image)); it returned a %s'], name, class(tracker));
  end
  if isfield(tracker, 'name') && ischar(tracker.name) && ~isempty(tracker.name)
    name = tracker.name(:)';
  end
end

% One message: name, args (a cell of unescaped strings), props (an N x 2
% cell of keys and values) and payload (the Base64 data of a memory image,
% read apart from the line; '' if none). ended is true at the end of input.
% Lines that do not start with @@TRAX: are skipped (the peer's own output).
function [msg, ended] = read_message()
  ended = false;
  while true
    [line, payload] = read_line();
    if ~ischar(line)
      ended = true;
      msg = [];
      return;
    end
    if strncmp(line, '@@TRAX:', 7)
      break;
    end
  end
  name = regexp(line(8:min(end, 64)), '^[A-Za-z0-9]*', 'match', 'once');
  rest = line(8 + numel(name):end);
  if isempty(name) || ~(isempty(rest) || rest(1) == ' ')
    error('malformed TraX line: %s', shorten(line));
  end
  msg.name = lower(name);
  msg.args = {};
  msg.props = cell(0, 2);
  msg.payload = payload;
  for token = split_tokens(rest, line)
    raw = token{1};
    key = regexp(raw(1:min(end, 65)), '^[A-Za-z0-9._]{1,64}=', 'match', 'once');
    if isempty(key)
      msg.args{end + 1} = unescape(raw);
    else
      msg.props(end + 1, :) = {key(1:end - 1), unescape(raw(numel(key) + 1:end))};
    end
  end
end

% One line of input without its newline (and a trailing \r), or -1 at the
% end of input. Read with fread: Octave's fgetl and fgets wait for the
% character after the newline (to tell the end of the input, for Matlab
% compatibility), which on a pipe deadlocks a protocol of questions and
% answers. One character at a time costs ~8 us, so when a line starts like a
% memory image its Base64 data is read with one fread (~2 ms for 320x240
% RGB) and returned apart, as payload, and the line keeps
% "image:W;H;FORMAT;" with empty data.
function [line, payload] = read_line()
  payload = '';
  line = blanks(0);
  in_data = false;                     % reading the last characters of the payload
  while true
    c = fread(stdin, 1, '*char');
    if isempty(c)                      % the end of the input
      if isempty(line) && isempty(payload)
        line = -1;
        return;
      end
      break;
    end
    if c == "\n"
      break;
    end
    if in_data
      if c == '"' || c == ' '
        in_data = false;
      else
        payload(end + 1) = c;
        continue;
      end
    end
    line(end + 1) = c;
    if c == ';' && isempty(payload) && numel(line) <= 96
      tok = regexp(line, '^@@TRAX:[A-Za-z]+ +"?image:(\d+);(\d+);(rgb|gray8|gray16);$', 'tokens', 'once');
      if ~isempty(tok)
        bytes = str2double(tok{1}) * str2double(tok{2}) * struct('rgb', 3, 'gray8', 1, 'gray16', 2).(tok{3});
        whole = 4 * floor(bytes / 3);  % the Base64 characters of the complete 3-byte groups
        payload = fread(stdin, whole, '*char')';
        in_data = true;                % then the padding, up to the quote or space
      end
    end
  end
  if ~isempty(line) && line(end) == "\r"
    line(end) = [];
  end
end

% The raw (still escaped) tokens of a message body: "quoted" (spaces
% allowed) or bare, separated by spaces; a backslash escapes the next
% character in both.
function tokens = split_tokens(body, line)
  tokens = {};
  n = numel(body);
  pos = 1;
  while pos <= n
    if body(pos) == ' '
      pos = pos + 1;
      continue;
    end
    quoted = body(pos) == '"';
    if quoted
      stops = '["\\]';
      j = pos + 1;
    else
      stops = '[ \\]';
      j = pos;
    end
    while true
      k = regexp(body(j:n), stops, 'once');
      if isempty(k)
        if quoted
          error('unterminated quoted argument in TraX line: %s', shorten(line));
        end
        j = n + 1;
        break;
      end
      j = j + k - 1;
      if body(j) == '\'
        if j == n
          error('TraX line ends inside an escape sequence: %s', shorten(line));
        end
        j = j + 2;
        continue;
      end
      break;                                   % the closing quote, or the space after a bare token
    end
    if quoted
      tokens{end + 1} = body(pos + 1:j - 1);
      pos = j + 1;
      if pos <= n && body(pos) ~= ' '
        error('no space after a quoted argument in TraX line: %s', shorten(line));
      end
    else
      tokens{end + 1} = body(pos:j - 1);
      pos = j;
    end
  end
end

% The escapes of the spec: \n is a newline, \X is X (as the reference library).
function out = unescape(text)
  if ~any(text == '\')
    out = text;
    return;
  end
  out = blanks(0);
  k = 1;
  while k <= numel(text)
    c = text(k);
    if c == '\' && k < numel(text)
      k = k + 1;
      c = text(k);
      if c == 'n'
        c = "\n";
      end
    end
    out(end + 1) = c;
    k = k + 1;
  end
end

function out = escape(text)
  out = strrep(strrep(strrep(text, '\', '\\'), '"', '\"'), "\n", '\n');
end

% HxWx3 uint8 RGB from a memory image (image:W;H;rgb|gray8|gray16;BASE64,
% the data possibly read apart as payload) or a path image (file://PATH).
function image = decode_image(arg, payload)
  if strncmp(arg, 'image:', 6)
    semis = find(arg(1:min(end, 64)) == ';', 3);
    if numel(semis) < 3
      error('bad memory image header %s', shorten(arg));
    end
    w = str2double(arg(7:semis(1) - 1));
    h = str2double(arg(semis(1) + 1:semis(2) - 1));
    format = arg(semis(2) + 1:semis(3) - 1);
    data = arg(semis(3) + 1:end);
    if isempty(data)
      data = payload;
    end
    bytes = matlab.net.base64decode(data);
    channels = struct('rgb', 3, 'gray8', 1, 'gray16', 2);
    if ~(w >= 1 && h >= 1 && w == round(w) && h == round(h) && isfield(channels, format))
      error('bad memory image header %s', shorten(arg));
    end
    if numel(bytes) ~= w * h * channels.(format)
      error('memory image %dx%d %s has %d bytes, not %d', w, h, format, numel(bytes), w * h * channels.(format));
    end
    switch format
      case 'rgb'
        image = permute(reshape(bytes, 3, w, h), [3 2 1]);
      case 'gray8'
        image = repmat(reshape(bytes, w, h)', [1 1 3]);
      otherwise                                 % gray16, little-endian
        values = double(bytes(1:2:end)) + 256 * double(bytes(2:2:end));
        image = repmat(uint8(round(reshape(values, w, h)' / 257)), [1 1 3]);
    end
  elseif strncmp(arg, 'data:', 5) || strncmp(arg, 'http', 4)
    error('image format not announced: %s', shorten(arg));
  else
    path = arg;
    if strncmp(path, 'file://', 7)
      path = path(8:end);
    end
    [image, map] = imread(path);
    if ~isempty(map)
      image = uint8(round(255 * ind2rgb(image, map)));
    end
    if isa(image, 'uint16')
      image = uint8(round(double(image) / 257));
    elseif ~isa(image, 'uint8')
      image = uint8(round(255 * double(image)));
    end
    if size(image, 3) == 1
      image = repmat(image, [1 1 3]);
    elseif size(image, 3) > 3
      image = image(:, :, 1:3);
    end
  end
end

% [x y w h] from a rectangle (x,y,w,h) or the bounding box of a polygon.
function box = parse_region(text)
  text = regexprep(strtrim(text), '^[a-z]+:', '');
  values = str2double(strsplit(text, ','));
  if numel(values) == 4 && all(isfinite(values))
    box = values;
  elseif numel(values) >= 6 && mod(numel(values), 2) == 0 && all(isfinite(values))
    xs = values(1:2:end);
    ys = values(2:2:end);
    box = [min(xs), min(ys), max(xs) - min(xs), max(ys) - min(ys)];
  else
    error('region %s is not a rectangle or a polygon', shorten(text));
  end
  if ~all(box(3:4) > 0)
    error('region %s has no area', shorten(text));
  end
end

function send_state(box, seconds)
  if isempty(box) || any(~isfinite(box(:)))
    region = '0';                              % a special region: no estimate in this frame
  else
    region = sprintf('%.4f,%.4f,%.4f,%.4f', double(box));
  end
  send(sprintf('@@TRAX:state "%s" "octave.time=%.6f"', region, seconds));
end

function send_quit(reason)
  send(['@@TRAX:quit "trax.reason=' escape(reason) '"']);
end

function send(line)
  fputs(stdout, [line "\n"]);
  fflush(stdout);
end

function status = protocol_error(what)
  send_quit(['sim4cv_trax_server: ' what]);
  status = 1;
end

function status = tracker_error(name, call, err)
  send_quit(sprintf('%s %s failed: %s', name, call, describe(err)));
  status = 1;
end

% An error's message with where it happened (function and line).
function text = describe(err)
  text = err.message;
  if ~isempty(err.stack)
    top = err.stack(1);
    text = sprintf('%s (in %s at line %d)', text, top.name, top.line);
  end
end

% What the tracker printed, or its error, copied to stderr (never stdout).
function forward(what)
  if ~ischar(what)                             % an error (MException, or a struct in some contexts)
    what = sprintf('error: %s\n', describe(what));
  end
  if ~isempty(what)
    fputs(stderr, what);
    if what(end) ~= "\n"
      fputs(stderr, "\n");
    end
    fflush(stderr);
  end
end

function ok = has_base64()
  try
    ok = isequal(matlab.net.base64decode('AQID'), uint8([1 2 3]));
  catch
    ok = false;
  end
end

function text = shorten(text)
  if numel(text) > 80
    text = [text(1:80) '...'];
  end
end
