// Built with `c++ pkgconfig_consumer.cpp $(pkg-config --cflags --libs hil)` against an installed hil:
// reads a rig file and prints its size and the volume of its first polyhedron.
#include <cstdio>
#include <exception>

#include <hil/contact_id/geometry.hpp>
#include <hil/format/rig.hpp>

int main(int argc, char** argv) try {
  if (argc != 2) {
    std::fprintf(stderr, "usage: pkgconfig_consumer RIG\n");
    return 2;
  }
  const auto rig = hil::format::load_rig(argv[1]);
  const auto& first = rig.objects.at(0).features.at(0).polyhedra.at(0);
  const auto poly = hil::contact_id::Polyhedron::from_vertices(first.vertices_m);
  std::printf("rig %s polyhedra %zu first volume %.6g faces %zu\n", rig.name.c_str(), hil::format::total_polyhedra(rig), poly.volume(),
              poly.faces().size());
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "pkgconfig_consumer: %s\n", e.what());
  return 1;
}
