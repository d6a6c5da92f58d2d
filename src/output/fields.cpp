#include "indentsim/output/fields.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "indentsim/base/file_system.hpp"

namespace indentsim {

NodalStresses average_to_nodes(const Mesh& mesh, const BulkModel& bulk) {
  NodalStresses nodal;
  nodal.values.assign(static_cast<std::size_t>(mesh.nodes()), {0, 0, 0, 0, 0});
  std::vector<int> count(static_cast<std::size_t>(mesh.nodes()), 0);
  // Bilinear extrapolation from the 2x2 Gauss points (at 1/2 -+ 1/(2 sqrt 3)) to the vertices:
  // in Gauss-point coordinates the vertices sit at 1/2 -+ sqrt(3)/2.
  const double lo = 0.5 - std::sqrt(3.0) / 2.0, hi = 0.5 + std::sqrt(3.0) / 2.0;
  const double vertex_s[4] = {lo, lo, hi, hi}, vertex_t[4] = {lo, hi, lo, hi};
  const int point_s[4] = {0, 0, 1, 1}, point_t[4] = {0, 1, 0, 1};
  // Averaged within one material region (docs/MODEL.md §14.1): a node on an interface takes the
  // side of the layer above it, as an average across would smear the jump of sigma_11 and sigma_33.
  const auto node_region = [&](int row) { return mesh.region(row < mesh.top_row() ? row : row - 1); };
  for (int ei = 0; ei < mesh.elements_x(); ++ei)
    for (int ej = 0; ej < mesh.elements_y(); ++ej) {
      const auto states = bulk.gauss_point_states(ei, ej);
      const auto nodes = mesh.element_nodes(ei, ej);
      for (int q = 0; q < 4; ++q) {
        if (mesh.region(ej) != node_region(q % 2 == 0 ? ej : ej + 1)) continue;
        std::array<double, 5> v{0, 0, 0, 0, 0};
        for (int g = 0; g < 4; ++g) {
          const double w = (point_s[g] ? vertex_s[q] : 1 - vertex_s[q]) * (point_t[g] ? vertex_t[q] : 1 - vertex_t[q]);
          v[0] += w * states[g].stress[0];
          v[1] += w * states[g].stress[1];
          v[2] += w * states[g].stress[2];
          v[3] += w * states[g].stress[3];
          v[4] += w * states[g].strain_intensity;
        }
        for (int c = 0; c < 5; ++c) nodal.values[nodes[q]][c] += v[c];
        ++count[nodes[q]];
      }
    }
  for (std::size_t n = 0; n < count.size(); ++n)
    for (double& c : nodal.values[n]) c /= count[n];
  return nodal;
}

std::string layers_csv(const std::vector<LineForce>& layers, double punch_force, const FieldFrame& frame, bool header) {
  std::string out = header ? "step,alpha,line,y,P_minus,P_plus,mismatch,P\n" : "";
  for (std::size_t j = 0; j < layers.size(); ++j) {
    const auto& l = layers[j];
    // Mismatch between the two sides of an interior line (the paper's P+ vs P-), relative to P.
    const double mismatch =
        std::isnan(l.below) || std::isnan(l.above) ? 0.0 : (l.below - l.above) / std::max(punch_force, 1e-300);
    out += fmt::format("{},{:.17g},{},{:.17g},{:.17g},{:.17g},{:.6e},{:.17g}\n", frame.step, frame.alpha, j, l.y, l.below,
                       l.above, mismatch, punch_force);
  }
  return out;
}

std::vector<int> profile_lines(const Mesh& mesh, const std::vector<double>& depths) {
  std::vector<int> lines{mesh.top_row()};
  for (double depth : depths) {
    int best = mesh.top_row();
    for (int j = 0; j < mesh.nodes_y(); ++j)
      if (std::abs(mesh.y(j) + depth) < std::abs(mesh.y(best) + depth)) best = j;
    lines.push_back(best);
  }
  return lines;
}

std::string profiles_csv(const Mesh& mesh, const std::vector<int>& lines, const std::vector<NodalLineForces>& layer,
                         const NodalStresses& nodal, const FieldFrame& frame, bool header) {
  // sigmaN_layer = sigma_N^- / w ~ sigma22 and sigmaT_layer = sigma_T^- / w ~ sigma12 just below
  // the line (from the local stiffness rows); the *_nodal columns are the Gauss-point stresses
  // averaged to the node.  The two views agree as the mesh is refined.
  std::string out =
      header ? "step,alpha,line,y,x,sigmaN_layer,sigmaT_layer,sigma22_nodal,sigma12_nodal,sigma11_nodal,e_u_nodal\n" : "";
  for (int j : lines)
    for (int i = 0; i < mesh.nodes_x(); ++i) {
      const int n = mesh.node(i, j);
      const double w = tributary_measure(mesh, i);
      const auto& s = nodal.values[n];
      // On the axis the u row carries the symmetry condition's reaction, not a stress: sigma12
      // vanishes there by symmetry.
      const double tangential = i == 0 ? 0.0 : layer[n].tangential_below / w;
      out += fmt::format("{},{:.17g},{},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g}\n", frame.step,
                         frame.alpha, j, mesh.y(j),
                         mesh.x(i), layer[n].normal_below / w, tangential, s[1], s[2], s[0], s[4]);
    }
  return out;
}

namespace {

// VTK XML "binary" arrays: base64 of a UInt64 byte count followed by the raw little-endian values
// (the VTKFile's header_type).  Five times smaller than ASCII and written without formatting a
// number: the ASCII writer spent most of a small elastic run's wall time (0.2 s of 0.45 s for 6
// frames of the paper mesh), and the values keep every bit.
void append_base64(std::string& out, const unsigned char* bytes, std::size_t size) {
  static constexpr char alphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  // Sized once and written through a pointer: appending a character at a time checked the
  // capacity four times per three bytes, and the fields' arrays are megabytes.
  const std::size_t start = out.size();
  out.resize(start + 4 * ((size + 2) / 3));
  char* p = out.data() + start;
  std::size_t k = 0;
  for (; k + 3 <= size; k += 3) {
    const unsigned v = (bytes[k] << 16) | (bytes[k + 1] << 8) | bytes[k + 2];
    *p++ = alphabet[(v >> 18) & 63];
    *p++ = alphabet[(v >> 12) & 63];
    *p++ = alphabet[(v >> 6) & 63];
    *p++ = alphabet[v & 63];
  }
  if (const std::size_t rest = size - k; rest > 0) {
    const unsigned v = (bytes[k] << 16) | (rest == 2 ? bytes[k + 1] << 8 : 0);
    *p++ = alphabet[(v >> 18) & 63];
    *p++ = alphabet[(v >> 12) & 63];
    *p++ = rest == 2 ? alphabet[(v >> 6) & 63] : '=';
    *p++ = '=';
  }
}

template <class T> constexpr const char* vtk_type();
template <> constexpr const char* vtk_type<double>() { return "Float64"; }
template <> constexpr const char* vtk_type<std::int32_t>() { return "Int32"; }
template <> constexpr const char* vtk_type<std::int64_t>() { return "Int64"; }
template <> constexpr const char* vtk_type<std::uint8_t>() { return "UInt8"; }

template <class T>
void binary_array(std::string& out, const char* name, int components, const std::vector<T>& values) {
  static_assert(std::endian::native == std::endian::little, "the VTU files declare LittleEndian");
  out += fmt::format("        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"binary\">\n          ",
                     vtk_type<T>(), name, components);
  // One base64 stream of header and data (VTK decodes the two together when they share it).
  std::vector<unsigned char> bytes(sizeof(std::uint64_t) + values.size() * sizeof(T));
  const std::uint64_t size = values.size() * sizeof(T);
  std::memcpy(bytes.data(), &size, sizeof size);
  if (!values.empty()) std::memcpy(bytes.data() + sizeof size, values.data(), size);
  append_base64(out, bytes.data(), bytes.size());
  out += "\n        </DataArray>\n";
}

template <class T, class F>
void data_array(std::string& out, const char* name, int components, std::size_t count, F value) {
  std::vector<T> values;
  values.reserve(count * static_cast<std::size_t>(components));
  for (std::size_t k = 0; k < count; ++k)
    for (int c = 0; c < components; ++c) values.push_back(static_cast<T>(value(k, c)));
  binary_array(out, name, components, values);
}

}  // namespace

std::array<double, 2> nodal_displacement(const Mesh& mesh, const double* u, int node) {
  const int eq_u = mesh.equation(Mesh::dof_u(node)), eq_v = mesh.equation(Mesh::dof_v(node));
  return {eq_u >= 0 ? u[eq_u] : 0.0, eq_v >= 0 ? u[eq_v] : 0.0};
}

std::string vtu_document(const FieldFrame& frame, const Mesh& mesh, const double* u, const BulkModel& bulk,
                         const NodalStresses& nodal, const ContactDiscretization& contact, const ContactResult& contact_state) {
  const auto nodes = static_cast<std::size_t>(mesh.nodes());
  const auto cells = static_cast<std::size_t>(mesh.elements());
  const auto displacement = [&](std::size_t n, int c) {
    return c < 2 ? nodal_displacement(mesh, u, static_cast<int>(n))[static_cast<std::size_t>(c)] : 0.0;
  };
  // Contact status per node: 1 in contact, 0 open candidate, -1 cannot touch the punch; sliding: 1
  // where friction slides (|q| = mu lambda).
  std::vector<int> status(nodes, -1), sliding(nodes, 0);
  std::vector<double> pressure(nodes, 0.0), shear(nodes, 0.0);
  for (std::size_t k = 0; k < contact.candidates().size(); ++k) {
    const auto& c = contact.candidates()[k];
    status[c.node] = contact_state.in_contact[k] ? 1 : 0;
    pressure[c.node] = c.tributary_measure > 0 ? contact_state.nodal_force[k] / c.tributary_measure : 0.0;
    // Friction's tangential force over the node's surface, along +x (docs/MODEL.md §3.3).
    shear[c.node] = c.tributary_measure > 0 ? contact_state.tangential_force[k] / c.tributary_measure : 0.0;
    sliding[c.node] = contact_state.sliding[k];
  }
  // Cell data: Gauss-point averages, the largest e_u, and the plastic flag.
  std::vector<std::array<double, 7>> cell(cells);
  for (int ei = 0; ei < mesh.elements_x(); ++ei)
    for (int ej = 0; ej < mesh.elements_y(); ++ej) {
      auto& c = cell[mesh.element(ei, ej)];
      c = {0, 0, 0, 0, 0, 0, 0};
      for (const GaussPointState& s : bulk.gauss_point_states(ei, ej)) {
        for (int k = 0; k < 4; ++k) c[k] += 0.25 * s.stress[k];
        c[4] = std::max(c[4], s.strain_intensity);
        c[5] += 0.25 * s.omega;
        c[6] += s.plastic ? 1 : 0;
      }
    }

  std::string out;
  out.reserve(nodes * 150);
  out += "<?xml version=\"1.0\"?>\n";
  out += "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n";
  // The depth and the increment as field data: the series' time value is the increment (alpha
  // repeats along a load history), and ParaView shows both per frame.
  out += fmt::format("    <FieldData>\n      <DataArray type=\"Float64\" Name=\"alpha\" NumberOfTuples=\"1\" "
                     "format=\"ascii\">{:.17g}</DataArray>\n      <DataArray type=\"Int32\" Name=\"step\" "
                     "NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>\n    </FieldData>\n",
                     frame.alpha, frame.step);
  out += fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", nodes, cells);
  out += "      <PointData Vectors=\"displacement\">\n";
  data_array<double>(out, "displacement", 3, nodes, displacement);
  // Component 33 is the out-of-plane stress of plane strain, the hoop stress of axisymmetry.
  const std::string third = mesh.kinematics().out_of_plane_stress();
  const std::string stress_names[5] = {"sigma11", "sigma22", "sigma12", third, "strain_intensity"};
  for (int c = 0; c < 5; ++c)
    data_array<double>(out, stress_names[c].c_str(), 1, nodes, [&](std::size_t n, int) { return nodal.values[n][c]; });
  data_array<std::int32_t>(out, "contact_status", 1, nodes, [&](std::size_t n, int) { return status[n]; });
  data_array<double>(out, "contact_pressure", 1, nodes, [&](std::size_t n, int) { return pressure[n]; });
  data_array<double>(out, "contact_shear_traction", 1, nodes, [&](std::size_t n, int) { return shear[n]; });
  data_array<std::int32_t>(out, "contact_sliding", 1, nodes, [&](std::size_t n, int) { return sliding[n]; });
  out += "      </PointData>\n      <CellData>\n";
  const std::string cell_names[6] = {"sigma11", "sigma22", "sigma12", third, "strain_intensity", "omega"};
  for (int c = 0; c < 6; ++c)
    data_array<double>(out, cell_names[c].c_str(), 1, cells, [&](std::size_t e, int) { return cell[e][c]; });
  data_array<std::int32_t>(out, "plastic", 1, cells, [&](std::size_t e, int) { return cell[e][6] > 0 ? 1 : 0; });
  data_array<std::int32_t>(out, "plastic_points", 1, cells, [&](std::size_t e, int) { return cell[e][6]; });
  // The material region (0 the substrate, k layer k from the surface; docs/MODEL.md §14.1).
  data_array<std::int32_t>(out, "region", 1, cells, [&](std::size_t e, int) {
    return mesh.region(static_cast<int>(e % static_cast<std::size_t>(mesh.elements_y())));
  });
  out += "      </CellData>\n      <Points>\n";
  data_array<double>(out, "coordinates", 3, nodes, [&](std::size_t n, int c) {
    const int i = static_cast<int>(n) / mesh.nodes_y(), j = static_cast<int>(n) % mesh.nodes_y();
    return c == 0 ? mesh.x(i) : c == 1 ? mesh.y(j) : 0.0;
  });
  out += "      </Points>\n      <Cells>\n";
  std::vector<std::int64_t> connectivity, offsets;
  connectivity.reserve(4 * cells);
  for (int ei = 0; ei < mesh.elements_x(); ++ei)
    for (int ej = 0; ej < mesh.elements_y(); ++ej)  // counter-clockwise, as VTK_QUAD wants
      for (int node : {mesh.node(ei, ej), mesh.node(ei + 1, ej), mesh.node(ei + 1, ej + 1), mesh.node(ei, ej + 1)})
        connectivity.push_back(node);
  for (std::size_t e = 1; e <= cells; ++e) offsets.push_back(static_cast<std::int64_t>(4 * e));
  binary_array(out, "connectivity", 1, connectivity);
  binary_array(out, "offsets", 1, offsets);
  binary_array(out, "types", 1, std::vector<std::uint8_t>(cells, 9));  // VTK_QUAD
  out += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  return out;
}

FieldSeries::FieldSeries(std::filesystem::path dir) : dir_(std::move(dir)), pvd_(dir_ / "fields.pvd") {
  std::filesystem::create_directories(dir_ / "fields");
}

void FieldSeries::add(int step, const std::string& vtu_text) {
  const std::string name = fmt::format("fields/step_{:06d}.vtu", step);
  write_file_atomically(dir_ / name, vtu_text);
  entries_.emplace_back(step, name);
  write_pvd();
}

void FieldSeries::add_existing(int step, const std::string& relative_file) {
  entries_.emplace_back(step, relative_file);
  write_pvd();
}

void FieldSeries::write_pvd() {
  std::string pvd = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  for (const auto& [time, file] : entries_)
    pvd += fmt::format("    <DataSet timestep=\"{}\" part=\"0\" file=\"{}\"/>\n", time, file);
  pvd += "  </Collection>\n</VTKFile>\n";
  write_file_atomically(pvd_, pvd);
}

}  // namespace indentsim
