// The Python binding: thin by design. It checks and converts arguments without copying (positions and particle
// attributes are read in place), releases the GIL, calls the core, and hands results back as numpy arrays that
// own the core's buffers. Core errors map one to one: InputError -> ValueError, FormatError -> meniscus.FormatError
// (a ValueError), ResourceError -> MemoryError.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli.h"
#include "base/errors.h"
#include "io/frame_pattern.h"
#include "io/io.h"
#include "parameters.h"
#include "io/partial_files.h"
#include "io/provenance.h"
#include "parameters_file.h"
#include "pipeline.h"
#include "sph/interior_fill.h"
#include "analysis/quality.h"
#include "analysis/scale_metrics.h"
#include "mesh/adjacency.h"
#include "mesh/blender_arrays.h"
#include "mesh/components.h"
#include "post/heat_smoothing.h"
#include "post/wall_constraints.h"

namespace py = pybind11;
using namespace meniscus;

namespace {

// Moves a vector into a numpy array without copying: the array owns the vector through a capsule.
template <class T>
py::array_t<T> to_numpy(std::vector<T>&& values, std::vector<py::ssize_t> shape) {
    auto* owner = new std::vector<T>(std::move(values));
    py::capsule capsule(owner, [](void* p) { delete static_cast<std::vector<T>*>(p); });
    return py::array_t<T>(shape, owner->data(), capsule);
}

// Checks a float array's dtype, layout and shape; names the argument and says what it got.
void require_float_array(const py::array& a, const std::string& name, bool allow_double, int columns) {
    const bool is_f32 = a.dtype().is(py::dtype::of<float>());
    const bool is_f64 = a.dtype().is(py::dtype::of<double>());
    if (!is_f32 && !(allow_double && is_f64))
        throw InputError(name + " must be " + (allow_double ? "float32 or float64" : "float32") + ", got dtype " +
                         py::str(a.dtype()).cast<std::string>());
    if (!(a.flags() & py::array::c_style)) throw InputError(name + " must be C-contiguous (use numpy.ascontiguousarray)");
    if (columns > 0 && (a.ndim() != 2 || a.shape(1) != columns))
        throw InputError(name + " must have shape (N, " + std::to_string(columns) + "), got " + py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim())))).cast<std::string>());
}

// Checks a face index array (a numpy array at all, then dtype, layout and shape) and names the argument.
py::array require_index_array(const py::handle& object, const std::string& name, int columns) {
    const std::string expected = name + " must be a C-contiguous int32 array of shape (N, " + std::to_string(columns) + ")";
    if (!py::isinstance<py::array>(object))
        throw InputError(expected + ", got " + py::str(py::type::of(object).attr("__name__")).cast<std::string>());
    const py::array a = py::reinterpret_borrow<py::array>(object);
    if (!a.dtype().is(py::dtype::of<int32_t>()) || !(a.flags() & py::array::c_style) || a.ndim() != 2 || a.shape(1) != columns)
        throw InputError(expected);
    return a;
}

// Attributes as numpy arrays: float32, or int32 for whole-number attributes (ids, labels), which the core carries
// in float (exact up to 2^24).
py::dict attributes_to_dict(std::vector<Attribute>&& attributes) {
    py::dict out;
    for (auto& a : attributes) {
        const py::ssize_t count = static_cast<py::ssize_t>(a.count());
        std::vector<py::ssize_t> shape = a.components == 1 ? std::vector<py::ssize_t>{count} : std::vector<py::ssize_t>{count, a.components};
        if (a.integral) {
            std::vector<int32_t> whole(a.values.size());
            for (std::size_t i = 0; i < whole.size(); ++i)
                whole[i] = std::isfinite(a.values[i]) ? static_cast<int32_t>(std::clamp(a.values[i], -2147483648.0f, 2147483520.0f)) : 0;
            out[py::str(a.name)] = to_numpy(std::move(whole), shape);
        } else {
            out[py::str(a.name)] = to_numpy(std::move(a.values), shape);
        }
    }
    return out;
}

// A per-element attribute given from Python: float32 arrays are read in place; integer and bool arrays (ids, labels,
// flags) are converted to float and marked whole-number.
struct AttributeArray {
    const float* values = nullptr;
    int components = 1;
    bool integral = false;
    std::vector<float> converted;
};

AttributeArray attribute_array(const py::handle& object, const std::string& name, std::size_t rows, const char* per_what) {
    if (!py::isinstance<py::array>(object)) throw InputError("attribute '" + name + "' must be a numpy array");
    const py::array a = py::reinterpret_borrow<py::array>(object);
    if (a.ndim() < 1 || a.ndim() > 2 || static_cast<std::size_t>(a.shape(0)) != rows)
        throw InputError("attribute '" + name + "' must have shape (N,) or (N, k) with N = " + std::to_string(rows) + " " + per_what);
    AttributeArray out;
    out.components = a.ndim() == 2 ? static_cast<int>(a.shape(1)) : 1;
    const char kind = a.dtype().kind();
    if (kind == 'i' || kind == 'u' || kind == 'b') {
        const py::array_t<double, py::array::c_style | py::array::forcecast> as_double(a);
        out.converted.assign(as_double.data(), as_double.data() + as_double.size());
        out.values = out.converted.data();
        out.integral = true;
        return out;
    }
    require_float_array(a, "attribute '" + name + "'", false, 0);
    out.values = static_cast<const float*>(a.data());
    return out;
}

py::dict mesh_to_dict(TriMesh&& mesh) {
    py::dict out;
    const py::ssize_t v = static_cast<py::ssize_t>(mesh.num_vertices()), f = static_cast<py::ssize_t>(mesh.num_triangles());
    const bool has_normals = !mesh.normals.empty();
    out["vertices"] = to_numpy(std::move(mesh.vertices), {v, 3});
    out["triangles"] = to_numpy(std::move(mesh.triangles), {f, 3});
    out["normals"] = has_normals ? py::object(to_numpy(std::move(mesh.normals), {v, 3})) : py::object(py::none());
    const py::ssize_t q = static_cast<py::ssize_t>(mesh.num_quads());
    out["quads"] = to_numpy(std::move(mesh.quads), {q, 4});
    out["attributes"] = attributes_to_dict(std::move(mesh.attributes));
    return out;
}

py::dict stats_to_dict(const PipelineStats& stats) {
    py::dict seconds, counts;
    for (const auto& s : stats.stage_seconds) seconds[py::str(s.first)] = s.second;
    for (const auto& c : stats.counts) counts[py::str(c.first)] = c.second;
    py::dict out;
    out["seconds"] = seconds;
    out["counts"] = counts;
    out["warnings"] = stats.warnings;
    return out;
}

PositionsView positions_view(const py::array& positions) {
    require_float_array(positions, "positions", true, 3);
    const std::size_t n = static_cast<std::size_t>(positions.shape(0));
    if (positions.dtype().is(py::dtype::of<float>())) return PositionsView(static_cast<const float*>(positions.data()), n);
    return PositionsView(static_cast<const double*>(positions.data()), n);
}

// A Python value for a parameter, as the schema's type asks: flags from True/False, counts from whole numbers,
// reals from any number. Errors name the parameter by its keyword.
double value_from_python(const ParameterSpec& spec, const py::handle& value) {
    const std::string got = py::repr(value).cast<std::string>();
    if (spec.type == ParameterType::flag) {
        const bool numpy_bool = py::hasattr(value, "dtype") && py::str(value.attr("dtype").attr("kind")).cast<std::string>() == "b";
        if (!py::isinstance<py::bool_>(value) && !numpy_bool) throw InputError(spec.name + " must be True or False, got " + got);
        return value.cast<bool>() ? 1.0 : 0.0;
    }
    if (!PyNumber_Check(value.ptr()) || py::isinstance<py::str>(value)) throw InputError(spec.name + " must be " + spec.allowed() + ", got " + got);
    return py::float_(py::reinterpret_borrow<py::object>(value)).cast<double>();
}

// Keyword arguments -> parameters: the one place Python values meet the schema. Unknown names, wrong types and
// values outside the allowed range are refused naming the keyword; a parameter not given keeps its default.
// A box corner: None (unset) or three numbers.
std::optional<Vector3> vector_from_python(const ParameterSpec& spec, const py::handle& value) {
    if (value.is_none()) return std::nullopt;
    const std::string got = py::repr(value).cast<std::string>();
    if (!py::isinstance<py::sequence>(value) || py::isinstance<py::str>(value) || py::len(value) != 3)
        throw InputError(spec.name + " must be None or three numbers (x, y, z), got " + got);
    Vector3 out{};
    const py::sequence items = py::reinterpret_borrow<py::sequence>(value);
    for (int k = 0; k < 3; ++k) {
        if (!PyNumber_Check(items[k].ptr())) throw InputError(spec.name + " must be None or three numbers (x, y, z), got " + got);
        out[k] = py::float_(items[k]).cast<double>();
    }
    return out;
}

Parameters parameters_from_python(const py::dict& values) {
    Parameters parameters;
    for (const auto& item : values) {
        const ParameterSpec& spec = find_parameter(py::str(item.first));
        if (spec.is_vector()) {
            const std::optional<Vector3> vector = vector_from_python(spec, item.second);
            if (auto problem = spec.problem(vector)) throw InputError(spec.name + " " + *problem);
            spec.set_vector(parameters, vector);
            continue;
        }
        const double value = value_from_python(spec, item.second);
        if (auto problem = spec.problem(value)) throw InputError(spec.name + " " + *problem);
        spec.set(parameters, value);
    }
    for (const auto& spec : parameter_schema())
        if (spec.required && !values.contains(spec.name)) throw InputError(spec.name + " is required (" + spec.help + ")");
    return parameters;
}

// A fluid domain (sph/fluid_domain.h) as a dict with the struct's field names, each optional; obstacles a list of
// (T, 3, 3) or flat float arrays of world-space triangles. Errors name the key.
template <class T>
T domain_field(const py::dict& values, const char* key, const char* expected, T value) {
    if (!values.contains(key)) return value;
    try {
        return values[key].cast<T>();
    } catch (const py::cast_error&) {
        throw InputError(std::string("fluid_domain['") + key + "'] must be " + expected + ", got " + py::repr(values[key]).cast<std::string>());
    }
}

// The dict's values without the checks a fill needs (a provenance record describes whatever was given).
FluidDomain fluid_domain_fields_from_python(const py::dict& values) {
    static const char* const keys[] = {"origin", "axes", "resolution", "closed_borders", "gravity", "band_width_cells", "obstacles",
                                       "object_to_world", "mesh_upres", "mesh_particle_radius", "mesh_smoothen_pos", "mesh_smoothen_neg",
                                       "mesh_concave_lower", "mesh_concave_upper"};
    for (const auto& item : values) {
        const std::string key = py::str(item.first);
        if (std::find_if(std::begin(keys), std::end(keys), [&](const char* k) { return key == k; }) != std::end(keys)) continue;
        std::string known;  // from the same list, so that the message names every key the check accepts
        for (const char* k : keys) known += (known.empty() ? "" : ", ") + std::string(k);
        throw InputError("fluid_domain has no key '" + key + "' (the keys are: " + known + ")");
    }
    FluidDomain d;
    d.origin = domain_field(values, "origin", "three numbers", d.origin);
    d.axes = domain_field(values, "axes", "three cell edges of three numbers each", d.axes);
    d.resolution = domain_field(values, "resolution", "three whole numbers", d.resolution);
    d.closed_borders = domain_field(values, "closed_borders", "six True/False (-x, +x, -y, +y, -z, +z)", d.closed_borders);
    d.gravity = domain_field(values, "gravity", "three numbers", d.gravity);
    d.band_width_cells = domain_field(values, "band_width_cells", "a number", d.band_width_cells);
    d.object_to_world = domain_field(values, "object_to_world", "sixteen numbers (a 4x4 matrix, column-major)", d.object_to_world);
    d.mesh_upres = domain_field(values, "mesh_upres", "a whole number (Mantaflow's Upres Factor)", d.mesh_upres);
    d.mesh_particle_radius = domain_field(values, "mesh_particle_radius", "a number", d.mesh_particle_radius);
    d.mesh_smoothen_pos = domain_field(values, "mesh_smoothen_pos", "a whole number", d.mesh_smoothen_pos);
    d.mesh_smoothen_neg = domain_field(values, "mesh_smoothen_neg", "a whole number", d.mesh_smoothen_neg);
    d.mesh_concave_lower = domain_field(values, "mesh_concave_lower", "a number", d.mesh_concave_lower);
    d.mesh_concave_upper = domain_field(values, "mesh_concave_upper", "a number", d.mesh_concave_upper);
    if (values.contains("obstacles"))
        for (const auto& soup : values["obstacles"].cast<py::list>()) {
            const py::array_t<float, py::array::c_style | py::array::forcecast> triangles(py::reinterpret_borrow<py::object>(soup));
            d.obstacles.emplace_back(triangles.data(), triangles.data() + triangles.size());
        }
    return d;
}

FluidDomain fluid_domain_from_python(const py::dict& values) {
    FluidDomain d = fluid_domain_fields_from_python(values);
    validate_fluid_domain(d);
    return d;
}

py::dict fluid_domain_to_python(const FluidDomain& d) {
    py::dict out;
    out["origin"] = d.origin;
    out["axes"] = d.axes;
    out["resolution"] = d.resolution;
    out["closed_borders"] = d.closed_borders;
    out["gravity"] = d.gravity;
    out["band_width_cells"] = d.band_width_cells;
    out["object_to_world"] = d.object_to_world;
    out["mesh_upres"] = d.mesh_upres;
    out["mesh_particle_radius"] = d.mesh_particle_radius;
    out["mesh_smoothen_pos"] = d.mesh_smoothen_pos;
    out["mesh_smoothen_neg"] = d.mesh_smoothen_neg;
    out["mesh_concave_lower"] = d.mesh_concave_lower;
    out["mesh_concave_upper"] = d.mesh_concave_upper;
    py::list obstacles;
    for (const std::vector<float>& soup : d.obstacles) obstacles.append(to_numpy(std::vector<float>(soup), {py::ssize_t(soup.size() / 9), 3, 3}));
    out["obstacles"] = obstacles;
    return out;
}

py::dict reconstruct(const py::array& positions, const py::dict& attributes, const py::dict& parameters, bool keep_raw_mesh,
                     const py::object& fluid_domain) {
    const PositionsView view = positions_view(positions);
    std::vector<AttributeInput> inputs;
    std::vector<AttributeArray> arrays;
    arrays.reserve(attributes.size());  // inputs point into the arrays' converted storage: no reallocation
    for (const auto& item : attributes) {
        const std::string name = py::str(item.first);
        arrays.push_back(attribute_array(item.second, name, view.count, "particles"));
        inputs.push_back({name, arrays.back().values, arrays.back().components, arrays.back().integral});
    }
    PipelineOptions options;
    static_cast<Parameters&>(options) = parameters_from_python(parameters);
    options.keep_raw_mesh = keep_raw_mesh;
    std::optional<FluidDomain> domain;
    if (!fluid_domain.is_none()) {
        if (!py::isinstance<py::dict>(fluid_domain))
            throw InputError("fluid_domain must be None or a dict (origin, axes, resolution, ...), got " + py::repr(fluid_domain).cast<std::string>());
        domain = fluid_domain_from_python(fluid_domain.cast<py::dict>());
        options.fluid_domain = &*domain;
    }

    PipelineResult result;
    {
        py::gil_scoped_release release;
        result = run_pipeline(view, inputs, options);
    }
    py::dict out = mesh_to_dict(std::move(result.mesh));
    out["raw"] = keep_raw_mesh ? py::object(mesh_to_dict(std::move(result.raw_mesh))) : py::object(py::none());
    out["stats"] = stats_to_dict(result.stats);
    out["weights_normalization"] = result.weights_normalization;
    return out;
}

py::dict read_particle_file(const std::string& path) {
    ParticleData data;
    {
        py::gil_scoped_release release;
        data = read_particles(path);
    }
    py::dict out;
    const py::ssize_t n = static_cast<py::ssize_t>(data.size());
    out["positions"] = to_numpy(std::move(data.positions), {n, 3});
    out["attributes"] = attributes_to_dict(std::move(data.attributes));
    out["fluid_domain"] = data.fluid_domain ? py::object(fluid_domain_to_python(*data.fluid_domain)) : py::object(py::none());
    return out;
}

TriMesh mesh_from_arrays(const py::array& vertices, const py::array& triangles, const py::object& normals, const py::dict& attributes,
                         const py::object& quads = py::none()) {
    require_float_array(vertices, "vertices", false, 3);
    require_index_array(triangles, "triangles", 3);
    TriMesh mesh;
    const float* v = static_cast<const float*>(vertices.data());
    mesh.vertices.assign(v, v + vertices.size());
    const int32_t* t = static_cast<const int32_t*>(triangles.data());
    mesh.triangles.assign(t, t + triangles.size());
    if (!quads.is_none()) {
        const py::array q = require_index_array(quads, "quads", 4);
        mesh.quads.assign(static_cast<const int32_t*>(q.data()), static_cast<const int32_t*>(q.data()) + q.size());
    }
    for (const std::vector<int32_t>* faces : {&mesh.triangles, &mesh.quads})
        for (int32_t index : *faces)
            if (index < 0 || static_cast<std::size_t>(index) >= mesh.num_vertices())
                throw InputError("faces refer to vertex " + std::to_string(index) + " but there are " + std::to_string(mesh.num_vertices()) + " vertices");
    if (!normals.is_none()) {
        const py::array n = py::reinterpret_borrow<py::array>(normals);
        require_float_array(n, "normals", false, 3);
        if (n.shape(0) != vertices.shape(0)) throw InputError("normals must have one row per vertex");
        mesh.normals.assign(static_cast<const float*>(n.data()), static_cast<const float*>(n.data()) + n.size());
    }
    for (const auto& item : attributes) {
        const std::string name = py::str(item.first);
        const AttributeArray a = attribute_array(item.second, name, mesh.num_vertices(), "vertices");
        Attribute out{name, a.components, {}, a.integral};
        out.values.assign(a.values, a.values + mesh.num_vertices() * static_cast<std::size_t>(a.components));
        mesh.attributes.push_back(std::move(out));
    }
    return mesh;
}

py::dict check_to_dict(const MeshCheck& c) {
    py::dict out;
    out["closed"] = c.closed();
    out["manifold"] = c.manifold();
    out["oriented"] = c.oriented();
    out["ok"] = c.ok();
    out["boundary_edges"] = c.boundary_edges;
    out["non_manifold_edges"] = c.non_manifold_edges;
    out["non_manifold_vertices"] = c.non_manifold_vertices;
    out["inconsistent_edges"] = c.inconsistent_edges;
    out["degenerate_triangles"] = c.degenerate_triangles;
    out["non_finite_vertices"] = c.non_finite_vertices;
    out["unreferenced_vertices"] = c.unreferenced_vertices;
    out["summary"] = c.summary();
    return out;
}


// The command line inside Python (the wheel's `meniscus` console script). Native code cannot see Ctrl-C, so the
// run asks Python between frames, and a pending KeyboardInterrupt stops it there.
int run_cli_in_python(const std::vector<std::string>& arguments) {
    CliHooks hooks;
    hooks.interrupted = [] {
        py::gil_scoped_acquire acquire;
        if (PyErr_CheckSignals() == 0) return false;
        PyErr_Clear();  // raised again below, once the run has returned
        return true;
    };
    int status;
    {
        py::gil_scoped_release release;
        status = run_cli(arguments, hooks);
    }
    if (status == kExitInterrupted) {
        PyErr_SetNone(PyExc_KeyboardInterrupt);
        throw py::error_already_set();
    }
    return status;
}

py::list schema_to_list() {
    static const char* const kTypes[] = {"flag", "count", "real", "vector3"};
    static const char* const kCliStyles[] = {"value", "on_off"};
    py::list out;
    for (const auto& spec : parameter_schema()) {
        py::dict d;
        d["name"] = spec.name;
        d["group"] = spec.group;
        d["type"] = kTypes[static_cast<int>(spec.type)];
        d["label"] = spec.label;
        d["cli"] = spec.cli;
        d["cli_style"] = kCliStyles[static_cast<int>(spec.cli_style)];
        d["unit"] = spec.unit;
        d["help"] = spec.help;
        d["default"] = spec.is_vector() ? py::object(py::none()) : py::object(py::float_(spec.default_value()));
        d["minimum"] = spec.minimum;
        d["maximum"] = spec.maximum;
        d["minimum_open"] = spec.minimum_open;
        d["maximum_open"] = spec.maximum_open;
        d["automatic"] = spec.automatic ? py::object(py::float_(*spec.automatic)) : py::object(py::none());
        d["automatic_word"] = spec.automatic_word;
        d["suggested"] = spec.suggested;
        d["soft_minimum"] = spec.soft_minimum;
        d["soft_maximum"] = spec.soft_maximum;
        d["required"] = spec.required;
        d["depends_on"] = spec.depends_on;
        d["allowed"] = spec.allowed();
        out.append(d);
    }
    return out;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
    m.doc() = "Meniscus native core: particle files, surface reconstruction and post-processing";
    m.attr("__version__") = MENISCUS_VERSION;

    static py::exception<FormatError> format_error(m, "FormatError", PyExc_ValueError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const FormatError& e) {
            PyErr_SetString(format_error.ptr(), e.what());
        } catch (const InputError& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        } catch (const ResourceError& e) {
            PyErr_SetString(PyExc_MemoryError, e.what());
        }
    });

    m.def("reconstruct", &reconstruct, py::arg("positions"), py::arg("attributes"), py::arg("parameters"),
          py::arg("keep_raw_mesh") = false, py::arg("fluid_domain") = py::none(),
          "Runs the pipeline on (N, 3) float32/float64 positions with parameters named as in parameter_schema(); "
          "returns a dict of numpy arrays and stats.");
    m.def("parameter_schema", &schema_to_list, "Every pipeline parameter: name, type, default, range, unit, help, spellings.");
    m.def("parameter_problem", [](const std::string& name, const py::object& value) -> py::object {
        const ParameterSpec& spec = find_parameter(name);
        std::optional<std::string> problem;
        try {
            problem = spec.is_vector() ? spec.problem(vector_from_python(spec, value)) : spec.problem(value_from_python(spec, value));
        } catch (const InputError& error) {
            const std::string message = error.what();
            problem = message.substr(std::min(message.size(), spec.name.size() + 1));
        }
        return problem ? py::object(py::str(*problem)) : py::object(py::none());
    }, py::arg("name"), py::arg("value"), "What is wrong with a value for a parameter ('must be ..., got ...'), or None.");
    // Provenance (io/provenance.h): the add-on's bakes and cache playback, and the farm's re-export check.
    m.def("provenance_record", [](const py::dict& parameters, const std::vector<std::string>& attributes, const std::string& source) {
        // reconstruct()'s fluid_domain, when given, shapes the mesh as much as the parameters do.
        py::dict values = parameters.attr("copy")();
        std::optional<FluidDomain> domain;
        if (values.contains("fluid_domain")) {
            const py::object given = values.attr("pop")("fluid_domain");
            if (!given.is_none()) domain = fluid_domain_fields_from_python(given.cast<py::dict>());
        }
        return provenance_record(parameters_from_python(values), attributes, source, domain ? &*domain : nullptr);
    }, py::arg("parameters"), py::arg("attributes"), py::arg("source"),
          "The provenance record of a mesh made from the particle file source with these reconstruct() parameters.");
    m.def("provenance_mismatch", &provenance_mismatch, py::arg("mesh_path"), py::arg("expected"),
          "Why the mesh file is not the one the record describes, in words; '' when it is.");
    m.def("forget_provenance", &forget_provenance, py::arg("mesh_path"), "Removes a mesh file's provenance record.");
    m.def("write_provenance", &write_provenance, py::arg("mesh_path"), py::arg("record"),
          "Writes a mesh file's provenance record (atomically).");
    // Writers' temporary files (io/partial_files.h): the add-on's bake names and cleans them as the command line does.
    m.def("partial_path", &partial_path, py::arg("target"), py::arg("process_id"),
          "The temporary name for writing target in process process_id.");
    m.def("remove_abandoned_partials", [](const std::string& folder) { return remove_abandoned_partials(folder); },
          py::arg("folder"), "Removes the temporary files of writers that are gone; returns their names.");
    m.attr("ABANDONED_PARTIAL_SECONDS") = kAbandonedPartialSeconds;
    // Frame ranges (native/cli/parameters_file.h): the farm's parameters files are bounded as the command line's.
    m.def("frame_number_problem", [](const py::int_& frame) -> py::object {
        int overflow = 0;
        const long long value = PyLong_AsLongLongAndOverflow(frame.ptr(), &overflow);
        if (overflow) return py::str("must be " + allowed_frame_numbers() + ", got " + py::repr(frame).cast<std::string>());
        const auto problem = frame_number_problem(value);
        return problem ? py::object(py::str(*problem)) : py::object(py::none());
    }, py::arg("frame"), "What is wrong with a frame number, or None.");
    m.def("frame_range_problem", [](long long first, long long last) -> py::object {
        const auto problem = frame_range_problem(first, last);
        return problem ? py::object(py::str(*problem)) : py::object(py::none());
    }, py::arg("first"), py::arg("last"), "What is wrong with frames first..last (bounded numbers), or None.");
    m.def("format_number", &format_number, py::arg("value"), "A number as people write it (0, 0.5, 2.5e-06).");
    m.def("run_cli", &run_cli_in_python, py::arg("arguments"),
          "Runs the meniscus command line (arguments[0] is the program name); returns the exit status.");
    // Frame patterns (io/frame_pattern.h): the rule the command line uses, for the Python API and the add-on.
    m.def("parse_frame_pattern", [](const std::string& path, std::optional<std::vector<std::string>> sibling_names) {
        const FramePattern p = parse_frame_pattern(path, sibling_names);
        return py::make_tuple(p.directory, p.prefix, p.suffix, p.padding);
    }, py::arg("path"), py::arg("sibling_names") = py::none(),
          "(directory, prefix, suffix, padding) of a '{}' / '####' pattern or a concrete numbered file.");
    m.def("match_frame", [](const std::string& prefix, const std::string& suffix, const std::string& name) -> py::object {
        const auto frame = FramePattern{"", prefix, suffix, 0}.match(name);
        return frame ? py::object(py::int_(*frame)) : py::object(py::none());
    }, py::arg("prefix"), py::arg("suffix"), py::arg("name"), "The frame number a file name stands for, or None.");
    m.def("list_frames", [](const std::string& directory, const std::string& prefix, const std::string& suffix, int padding) {
        FrameListing listing;
        {
            py::gil_scoped_release release;
            listing = list_frames(FramePattern{directory, prefix, suffix, padding});
        }
        return py::make_tuple(listing.frames, listing.duplicates);
    }, py::arg("directory"), py::arg("prefix"), py::arg("suffix"), py::arg("padding"),
          "({frame: path}, duplicate notes) of the files of a pattern in its folder.");
    m.def("read_particles", &read_particle_file, py::arg("path"), "Reads a particle file: dict with 'positions' (N, 3) float32 and 'attributes'.");
    m.def("read_mesh", [](const std::string& path) {
        TriMesh mesh;
        {
            py::gil_scoped_release release;
            mesh = read_mesh(path);
        }
        return mesh_to_dict(std::move(mesh));
    }, py::arg("path"));
    m.def("write_mesh", [](const std::string& path, const py::array& vertices, const py::array& triangles, const py::object& normals,
                           const py::dict& attributes, const py::object& quads) {
        TriMesh mesh = mesh_from_arrays(vertices, triangles, normals, attributes, quads);
        py::gil_scoped_release release;
        write_mesh(mesh, path);
    }, py::arg("path"), py::arg("vertices"), py::arg("triangles"), py::arg("normals") = py::none(), py::arg("attributes") = py::dict(),
       py::arg("quads") = py::none());
    m.def("blender_mesh_arrays", [](const py::object& triangles, const py::object& quads, int64_t vertex_count, int threads) {
        py::array t = require_index_array(triangles, "triangles", 3);  // not const: a view of it may be returned
        const py::array q = quads.is_none() ? py::array(py::array_t<int32_t>(std::vector<py::ssize_t>{0, 4})) : require_index_array(quads, "quads", 4);
        BlenderMeshArrays arrays;
        {
            py::gil_scoped_release release;
            arrays = blender_mesh_arrays(static_cast<const int32_t*>(t.data()), t.shape(0), static_cast<const int32_t*>(q.data()),
                                         q.shape(0), vertex_count, threads);
        }
        py::dict out;
        const py::ssize_t corners = 3 * t.shape(0) + 4 * q.shape(0);
        const py::ssize_t faces_count = static_cast<py::ssize_t>(arrays.face_offsets.size());
        const py::ssize_t edges = static_cast<py::ssize_t>(arrays.edges.size() / 2);
        // Without quads the core made no copy: the corners are the triangles' own indices, a view of them.
        out["corner_vertices"] = q.shape(0) > 0 ? py::object(to_numpy(std::move(arrays.corner_vertices), {corners}))
                                                : py::object(t.reshape(std::vector<py::ssize_t>{t.size()}));
        out["face_offsets"] = to_numpy(std::move(arrays.face_offsets), {faces_count});
        out["edges"] = arrays.has_edges ? py::object(to_numpy(std::move(arrays.edges), {edges, 2})) : py::object(py::none());
        out["corner_edges"] = arrays.has_edges ? py::object(to_numpy(std::move(arrays.corner_edges), {corners})) : py::object(py::none());
        return out;
    }, py::arg("triangles"), py::arg("quads"), py::arg("vertex_count"), py::arg("threads") = 0,
       "A mesh in Blender's layout: corner_vertices (C,), face_offsets (F,), edges (E, 2) and corner_edges (C,) int32 "
       "(those two None when a face repeats a vertex); see native/core/mesh/blender_arrays.h.");
    m.def("check_mesh", [](const py::array& vertices, const py::array& triangles) {
        TriMesh mesh = mesh_from_arrays(vertices, triangles, py::none(), py::dict());
        MeshCheck check;
        {
            py::gil_scoped_release release;
            check = check_mesh(mesh);
        }
        return check_to_dict(check);
    }, py::arg("vertices"), py::arg("triangles"));
    m.def("assess_quality", [](const py::array& vertices, const py::array& triangles, int threads, double scale_length, double raw_mean_edge) {
        TriMesh mesh = mesh_from_arrays(vertices, triangles, py::none(), py::dict());
        MeshQuality q;
        {
            py::gil_scoped_release release;
            q = assess_quality(mesh, threads, scale_length, raw_mean_edge);
        }
        py::dict out;
        out["check"] = check_to_dict(q.check);
        out["vertices"] = q.vertices;
        out["triangles"] = q.triangles;
        out["volume"] = q.volume;
        out["area"] = q.area;
        py::list components;
        for (const auto& c : q.components) components.append(py::make_tuple(c.triangles, c.volume));
        out["components"] = components;
        out["bumpiness"] = q.bumpiness;
        out["mean_normal_angle_deg"] = q.mean_normal_angle_deg;
        out["valence_histogram"] = q.valence_histogram;
        out["single_vertex_configurations"] = q.single_vertex_configurations;
        out["double_vertex_configurations"] = q.double_vertex_configurations;
        out["mean_edge_length"] = q.mean_edge_length;
        if (q.scale_length > 0.0) {
            out["scale_length"] = q.scale_length;
            out["hfl_passes"] = q.hfl_passes;
            out["hfl"] = q.hfl;
            out["heat_bumpiness"] = q.heat_bumpiness;
        }
        return out;
    }, py::arg("vertices"), py::arg("triangles"), py::arg("threads") = 0, py::arg("scale_length") = 0.0, py::arg("raw_mean_edge") = 0.0);
    // Measures and the smoothing stage on their own, for the benchmarks and tests (bench/smoothing_scale.py).
    m.def("taubin_distance", [](const py::array& vertices, const py::array& triangles, int passes, int threads) {
        TriMesh mesh = mesh_from_arrays(vertices, triangles, py::none(), py::dict());
        py::gil_scoped_release release;
        return taubin_distance(mesh, build_adjacency(mesh, resolve_threads(threads)), passes, threads);
    }, py::arg("vertices"), py::arg("triangles"), py::arg("passes"), py::arg("threads") = 0);
    m.def("heat_distance", [](const py::array& vertices, const py::array& triangles, double length, int threads) {
        TriMesh mesh = mesh_from_arrays(vertices, triangles, py::none(), py::dict());
        py::gil_scoped_release release;
        return heat_distance(mesh, build_adjacency(mesh, resolve_threads(threads)), length, threads);
    }, py::arg("vertices"), py::arg("triangles"), py::arg("length"), py::arg("threads") = 0);
    m.def("mean_edge_length", [](const py::array& vertices, const py::array& triangles) {
        TriMesh mesh = mesh_from_arrays(vertices, triangles, py::none(), py::dict());
        py::gil_scoped_release release;
        return mean_edge_length(mesh, build_adjacency(mesh, 1), 1);
    }, py::arg("vertices"), py::arg("triangles"));
    m.def("component_summary", [](const py::array& vertices, const py::array& triangles) {
        TriMesh mesh = mesh_from_arrays(vertices, triangles, py::none(), py::dict());
        ComponentSummary c;
        {
            py::gil_scoped_release release;
            c = component_summary(mesh);
        }
        const py::ssize_t n = static_cast<py::ssize_t>(c.volume.size());
        return py::make_tuple(to_numpy(std::move(c.volume), {n}), to_numpy(std::move(c.centroid), {n, 3}));
    }, py::arg("vertices"), py::arg("triangles"), "(volume (C,), centroid (C, 3)) per connected component with triangles.");
    m.def("heat_smooth", [](const py::array& vertices, const py::array& triangles, const py::object& weights, double reach,
                            double particle_radius, bool local_return, bool volume_correction, int parts, double part_time, double return_tolerance, double local_scale, double aggregate_size, const py::object& wall_mask,
                            const py::object& wall_planes, int threads) {
        TriMesh mesh = mesh_from_arrays(vertices, triangles, py::none(), py::dict());
        std::vector<float> w;
        if (!weights.is_none()) w = weights.cast<std::vector<float>>();
        WallConstraints walls;
        if (!wall_mask.is_none()) {
            walls.mask = wall_mask.cast<std::vector<uint8_t>>();
            const std::vector<float> planes = wall_planes.cast<std::vector<float>>();
            if (planes.size() != 6) throw InputError("wall_planes: 6 values (min x, max x, min y, max y, min z, max z)");
            std::copy(planes.begin(), planes.end(), walls.planes.begin());
        }
        HeatSmoothingSettings settings;
        settings.reach = reach;
        settings.particle_radius = particle_radius;
        settings.local_return = local_return;
        settings.volume_correction = volume_correction;
        settings.parts = parts;
        settings.part_time = part_time;
        settings.return_tolerance = return_tolerance;
        settings.local_scale = local_scale;
        settings.aggregate_size = aggregate_size;
        settings.max_offset = 4.0 * particle_radius;
        settings.walls = walls.empty() ? nullptr : &walls;
        HeatSmoothingReport report;
        {
            py::gil_scoped_release release;
            const MeshAdjacency adjacency = build_adjacency(mesh, resolve_threads(threads));
            report = heat_smooth(mesh, adjacency, w, settings, threads);
        }
        py::dict info;
        info["edge"] = report.edge;
        info["iterations"] = report.iterations;
        info["parts"] = report.parts;
        info["applications"] = report.applications;
        info["reverted_components"] = report.reverted_components;
        info["coarse_applications"] = report.coarse_applications;
        info["aggregates"] = report.aggregates;
        info["coarse_edge"] = report.coarse_edge;
        info["seconds"] = py::dict(py::arg("flow") = report.seconds_flow,
                                   py::arg("return") = report.seconds_return, py::arg("correction") = report.seconds_correction);
        const py::ssize_t n = static_cast<py::ssize_t>(mesh.num_vertices());
        return py::make_tuple(to_numpy(std::move(mesh.vertices), {n, 3}), info);
    }, py::arg("vertices"), py::arg("triangles"), py::arg("weights") = py::none(), py::arg("reach") = 0.0, py::arg("particle_radius") = 0.0,
       py::arg("local_return") = true, py::arg("volume_correction") = true, py::arg("parts") = 0, py::arg("part_time") = 0.0, py::arg("return_tolerance") = 0.0, py::arg("local_scale") = 0.0, py::arg("aggregate_size") = -1.0, py::arg("wall_mask") = py::none(),
       py::arg("wall_planes") = py::none(), py::arg("threads") = 0,
       "The physical-reach smoothing stage (post/heat_smoothing.h; the default) on a mesh: reach and "
       "particle_radius absolute; returns (vertices (V, 3) float32, report dict).");
}
