// GetWorld: the world as it is (every answer carries its WorldInfo), and
// with with_map_text the loaded map's canonical text. Only asks: nothing
// to publish afterwards.
#include "server/daemon/configure_request.h"
#include "server/sim/map/map_text.h"

namespace sim4cv::daemon::configure {

extern const ConfigureRequest kGetWorld{
    proto::Configure::kGetWorld,
    [](Simulation& simulation, const proto::Configure& request, proto::Configured& answer, Simulation::Change& change) {
      if (request.get_world().with_map_text() && simulation.scene().map) {
        answer.set_map_text(map::WriteMap(*simulation.scene().map));
      }
      change.world_changed = false;
    }};

}  // namespace sim4cv::daemon::configure
