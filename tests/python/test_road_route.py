"""QueryRoad.route: the road query measured against one route's lane, on a
crossroads whose route turns left. After a missed turn the offset is to the
route's lane (as the closed-loop evaluation's RoutePath measures it), not
0 m to the straight-on lane the car took; through the left turn the nearest
point stays on the turn's arc, where the plain query jumps between lanes."""

import math
import os
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

import sim4cv  # noqa: E402
from sim4cv import driving_dataset as dd  # noqa: E402
from sim4cv import driving_metrics as dm  # noqa: E402
from sim4cv import sim4cv_pb2 as pb  # noqa: E402
from sim4cv.daemon import OwnDaemon  # noqa: E402
from sim4cv.errors import ServerError  # noqa: E402

# test_driving_guided's lattice: a ring of 5 x 5 tiles with a crossroads at the origin (tile 2,2);
# its route "left" comes from the south and turns left (west) there.
from test_driving_guided import LATTICE  # noqa: E402


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    path = tmp_path_factory.mktemp("road") / "lattice.map"
    path.write_text(LATTICE)
    with OwnDaemon(["--map", str(path), "--traffic-cars", "0", "--traffic-parked", "0",
                    "--traffic-pedestrians", "0"], mode="lockstep") as daemon, \
            sim4cv.connect(daemon.address, name="road_route_test", timeout=30.0) as client:
        yield client, dd.RoutePath(dd.parse_map(str(path)), "left")


def _route_deviation(path, x, y):
    """Signed (+ right) distance to the route's lane, as driving_eval measures it."""
    return min((dm.signed_distance_to_segment(x, y, segment)[1] for segment in path.segments), key=abs)


def test_after_a_missed_turn_the_offset_is_to_the_routes_lane(setup):
    client, path = setup
    x, y = 2.0, 20.0  # on the northbound lane past the crossroads: the car went straight on
    plain = client.query_road(x, y)
    assert plain.distance == pytest.approx(0.0, abs=1e-9)
    routed = client.query_road(x, y, route="left")
    # the nearest point of the route's lanes: on the left turn's arc (radius 12 m about (-10, -10))
    assert routed.distance == pytest.approx(math.hypot(30.0, 12.0) - 12.0, abs=1e-9)
    assert -routed.lateral_offset == pytest.approx(_route_deviation(path, x, y), abs=1e-9)


def test_through_the_left_turn_the_route_keeps_its_arc(setup):
    client, path = setup
    start = path.segments[1][0]  # the turn, after the straight of tile 1,2
    length = path.segments[1][1]
    segments, plain_segments = set(), set()
    for k in range(1, 40):
        u = start + length * k / 40
        x, y, heading = path.point(u)
        px, py = x + 0.3 * math.sin(heading), y - 0.3 * math.cos(heading)  # 0.3 m right of the lane centre
        routed = client.query_road(px, py, route="left")
        assert routed.lateral_offset == pytest.approx(-0.3, abs=1e-9)
        assert -routed.lateral_offset == pytest.approx(_route_deviation(path, px, py), abs=1e-9)
        segments.add(routed.nearest.segment)
        plain_segments.add(client.query_road(px, py, heading_deg=math.degrees(heading)).nearest.segment)
    assert len(segments) == 1  # one arc all the way through
    assert len(plain_segments) > 1  # the plain query meets other lanes in the junction

    # the points ahead turn with the route: 4 points from 6 m before the junction end up heading west
    x, y, _ = path.point(start - 6.0)
    routed = client.query_road(x, y, count=4, step=4.0, route="left")
    straight = client.query_road(x, y, count=4, step=4.0, heading_deg=90.0)
    assert routed.ahead[-1].position.x < 0.0 and routed.ahead[-1].heading_deg > 135  # into the turn
    assert straight.ahead[-1].position.x == pytest.approx(2.0, abs=1e-9)


def test_an_unknown_route_is_refused_naming_the_maps_routes(setup):
    client, _ = setup
    with pytest.raises(ServerError) as e:
        client.query_road(0.0, 0.0, route="turn_right")
    assert e.value.code == pb.ERROR_CODE_INVALID_ARGUMENT
    assert "QueryRoad.route 'turn_right': scene 'lattice' has no such route; its routes: 'loop', 'left'," in str(e.value)
