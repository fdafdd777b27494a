function box = ssd_tracker_loop(address, frames)
% SSD_TRACKER_LOOP  The complete tracker loop of docs/clients.md: a template
% tracker (the sum of squared differences over a +-8 pixel search) starts
% from the car's ground-truth box and answers every lockstep frame.
%   box = ssd_tracker_loop('shm:///sim4cv', 300)   % the last box, [x y w h]
h = sim4cv_connect(address, 'ssd-tracker');
sim4cv_subscribe(h, 'uav', {'rgb', 'boxes'}, 'lockstep');
f = sim4cv_frame(h, 'step');
b = f.boxes([f.boxes.object_id] == 1);              % the car's ground truth, 0-based pixels
box = round([b.x b.y b.width b.height]);
image = mean(double(f.rgb), 3);
template = image(box(2) + (1:box(4)), box(1) + (1:box(3)));
for k = 1:frames
  f = sim4cv_frame(h, 'step');  image = mean(double(f.rgb), 3);  best = inf;  at = box(1:2);
  for dy = -8:8, for dx = -8:8                         % every placement around the last box
    x = box(1) + dx;  y = box(2) + dy;
    if x < 0 || y < 0 || x + box(3) > f.width || y + box(4) > f.height, continue; end
    d = sum(sum((image(y + (1:box(4)), x + (1:box(3))) - template) .^ 2));
    if d < best, best = d; at = [x y]; end
  end, end
  box(1:2) = at;
  sim4cv_send_box(h, f.frame_id, box, 1);
end
sim4cv_close(h);
end
