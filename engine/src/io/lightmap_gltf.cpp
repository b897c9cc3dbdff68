#include <hemi/io/lightmap_gltf.h>

#include "gltf_builder.h"

#include <hemi/io/half_scale.h>

#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::io
{

std::array<uint8_t, 4> encode_rgbm(glm::vec3 value, float range)
{
    const glm::vec3 v = glm::clamp(value, glm::vec3(0.0f), glm::vec3(range));
    const float m = std::max({v.r, v.g, v.b});
    if (!(m > 0.0f))
        return {0, 0, 0, 0};
    const float a = std::clamp(std::ceil(m / range * 255.0f), 1.0f, 255.0f);
    const float scale = 255.0f / (a / 255.0f * range);
    auto code = [&](float c) { return uint8_t(std::clamp(std::lround(c * scale), 0l, 255l)); };
    return {code(v.r), code(v.g), code(v.b), uint8_t(a)};
}

LightmapGltfSummary write_lightmap_gltf(const std::filesystem::path& path, const LightmapAsset& asset,
                                        const LightmapGltfOptions& options)
{
    const std::string cannot = "hemi: cannot export " + path.string() + ": ";
    std::vector<const LightmapOutput*> stored;
    if (options.outputs.empty() && options.all_outputs)
        for (const LightmapOutput& o : asset.outputs)
            stored.push_back(&o);
    for (const std::string& name : options.outputs)
        stored.push_back(&asset.output(name)); // throws naming the outputs the asset has
    const LightmapOutput* plain = nullptr;
    for (const LightmapOutput& o : asset.outputs)
        if (o.name == "plain")
            plain = &o;
    if (!plain)
        throw std::invalid_argument(cannot + "the asset has no \"plain\" output, which the RGBM lightmap is "
                                             "made of (bake it with --bases including plain)");

    const uint32_t w = asset.width, h = asset.height;
    // A glTF image is the whole atlas: viewers and engines load nothing larger than 16384 a side.
    if (w > 16384 || h > 16384)
        throw std::invalid_argument(cannot + "its lightmap atlas is " + std::to_string(w) + "x" +
                                    std::to_string(h) +
                                    ", and a glTF image of the whole atlas may be at most 16384 a side "
                                    "(hemi draws it from pages; rebake with a smaller --size to export)");
    LightmapGltfSummary summary;
    float range = options.rgbm_range;
    if (range == 0.0f)
    {
        for (float v : plain->maps.values)
            range = std::max(range, v);
        if (range == 0.0f)
            range = 1.0f;
    }
    if (!std::isfinite(range) || range <= 0.0f)
        throw std::invalid_argument(cannot + "the RGBM range must be finite and positive");
    summary.rgbm_range = range;

    // The buffer's size before anything is built: a .glb's chunk lengths are 32-bit.
    uint64_t bytes = 0;
    for (const LightmapOutput* o : stored)
        bytes += uint64_t(w) * h * o->k * 6;
    if (bytes > (uint64_t(1) << 32) - (uint64_t(1) << 28))
        throw std::invalid_argument(cannot + "the outputs' half floats alone take " +
                                    std::to_string(bytes >> 20) +
                                    " MiB, more than one glTF buffer holds (4 GiB); store fewer outputs");

    // The RGBM lightmap.
    ImageRgba8 rgbm{w, h, std::vector<uint8_t>(size_t(w) * h * 4)};
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            const glm::vec3 v = plain->maps.at(0, x, y);
            if (glm::any(glm::greaterThan(v, glm::vec3(range))) ||
                glm::any(glm::lessThan(v, glm::vec3(0.0f))))
                ++summary.clipped_texels;
            const std::array<uint8_t, 4> c = encode_rgbm(v, range);
            std::copy(c.begin(), c.end(), rgbm.pixels.begin() + (size_t(y) * w + x) * 4);
        }

    GltfScene scene;
    scene.mesh = asset.mesh;
    scene.materials = asset.materials;
    scene.images = asset.images;
    scene.primitives = asset.primitives;
    detail::GltfBuilder b = detail::scene_builder(
        path, scene, std::vector<ImageStorage>(scene.images.size(), ImageStorage::BufferView));
    tinygltf::Model& m = b.m;

    tinygltf::Sampler sampler; // no mipmaps: a coarser level would mix neighbouring charts
    sampler.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
    sampler.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
    sampler.wrapS = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
    sampler.wrapT = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
    m.samplers.push_back(sampler);
    // An atlas-sized PNG in the buffer, as a texture with that sampler: its index.
    const auto add_texture = [&](const ImageRgba8& pixels, const std::string& name)
    {
        const std::vector<uint8_t> png = encode_png(pixels);
        tinygltf::Image image;
        image.name = name;
        image.bufferView = b.view(png.data(), png.size(), 0);
        image.mimeType = "image/png";
        m.images.push_back(image);
        tinygltf::Texture texture;
        texture.name = name;
        texture.source = int(m.images.size() - 1);
        texture.sampler = int(m.samplers.size() - 1);
        m.textures.push_back(texture);
        return int(m.textures.size() - 1);
    };
    const int lightmap = add_texture(rgbm, "hemi lightmap (RGBM)");

    using Value = tinygltf::Value;
    auto number = [](double v) { return Value(v); };
    auto vec3 = [&](const glm::vec3& v) {
        return Value(Value::Array{number(v.x), number(v.y), number(v.z)});
    };
    for (tinygltf::Material& mat : m.materials)
    {
        Value::Object extras;
        if (mat.extras.IsObject())
            for (const std::string& key : mat.extras.Keys())
                extras[key] = mat.extras.Get(key);
        Value::Object info;
        info["index"] = Value(lightmap);
        info["texCoord"] = Value(1);
        info["encoding"] = Value(std::string("RGBM"));
        info["range"] = number(range);
        extras["lightmap"] = Value(info);
        mat.extras = Value(extras);
    }

    Value::Object ext;
    ext["width"] = Value(int(w));
    ext["height"] = Value(int(h));
    ext["texCoord"] = Value(1);
    ext["rays"] = Value(int(asset.rays));
    ext["bounces"] = Value(int(asset.bounces));
    Value::Object rgbm_info;
    rgbm_info["index"] = Value(lightmap);
    rgbm_info["range"] = number(range);
    ext["rgbm"] = Value(rgbm_info);
    Value::Array outputs;
    for (const LightmapOutput* o : stored)
    {
        // Light of any magnitude: the halves are the values / scale, a power of two (io/half_scale.h).
        const int exponent = half_scale_exponent(largest_magnitude(o->maps.values));
        std::vector<uint16_t> halves(size_t(w) * h * o->k * 3);
        size_t i = 0;
        for (uint32_t k = 0; k < o->k; ++k)
            for (uint32_t y = 0; y < h; ++y)
                for (uint32_t x = 0; x < w; ++x)
                {
                    const glm::vec3 v = o->maps.at(k, x, y);
                    for (int c = 0; c < 3; ++c)
                        halves[i++] = glm::packHalf1x16(std::ldexp(v[c], -exponent));
                }
        Value::Object out;
        out["name"] = Value(o->name);
        out["coefficients"] = Value(int(o->k));
        out["format"] = Value(std::string("RGB16F"));
        out["scale"] = number(std::ldexp(1.0, exponent));
        out["bufferView"] = Value(b.view(halves.data(), halves.size() * 2, 0));
        outputs.push_back(Value(out));
        summary.outputs.push_back(o->name);
    }
    if (!outputs.empty()) // (tinygltf writes an empty array as null)
        ext["outputs"] = Value(outputs);
    if (!asset.probes.empty())
    {
        const LightProbes& p = asset.probes;
        Value::Object probes;
        probes["count"] =
            Value(Value::Array{Value(int(p.count.x)), Value(int(p.count.y)), Value(int(p.count.z))});
        probes["min"] = vec3(p.lo);
        probes["max"] = vec3(p.hi);
        probes["irradiance"] =
            Value(b.view(p.irradiance.data(), p.irradiance.size() * sizeof(p.irradiance[0]), 0));
        probes["valid"] = Value(b.view(p.valid.data(), p.valid.size(), 0));
        if (p.scattered()) // each probe's position and reach
            probes["points"] = Value(b.view(p.points.data(), p.points.size() * sizeof(p.points[0]), 0));
        if (!p.depth.empty()) // what each probe sees, for the lookup that leaves out the probes behind walls
        {
            Value::Object depth;
            depth["resolution"] = Value(int(p.depth_resolution));
            depth["maxDistance"] = number(p.max_distance);
            depth["bufferView"] = Value(b.view(p.depth.data(), p.depth.size() * sizeof(p.depth[0]), 0));
            probes["depth"] = Value(depth);
        }
        ext["probes"] = Value(probes);
    }
    // Mixed lights: the shadowmask as an RGBA8 PNG of the atlas (data, not colour: channel c / 255 is the
    // share of the direct light of the mixed light of channel c that reaches the texel), and every light with
    // its bake mode.
    if (asset.shadowmask.k == 4)
    {
        ImageRgba8 mask{w, h, std::vector<uint8_t>(size_t(w) * h * 4, 0)};
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x)
                for (uint32_t c = 0; c < 4; ++c)
                    mask.pixels[(size_t(y) * w + x) * 4 + c] =
                        uint8_t(std::lround(std::clamp(asset.shadowmask.at(c, x, y).x, 0.0f, 1.0f) * 255.0f));
        const int mask_texture = add_texture(mask, "hemi shadowmask");
        Value::Object shadowmask;
        shadowmask["index"] = Value(mask_texture);
        shadowmask["texCoord"] = Value(1);
        ext["shadowmask"] = Value(shadowmask);
    }
    if (!asset.lights.empty())
    {
        static const char* const types[] = {"directional", "point", "spot"};
        Value::Array lights;
        for (const LightmapLight& l : asset.lights)
        {
            const PunctualLight& p = l.light;
            Value::Object light;
            light["name"] = Value(p.name);
            light["type"] = Value(std::string(types[int(p.type)]));
            light["mode"] = Value(std::string(light_mode_name(p.mode)));
            if (l.channel >= 0)
                light["shadowmaskChannel"] = Value(l.channel);
            light["color"] = vec3(p.color);
            light["intensity"] = number(p.intensity);
            if (p.type != PunctualLight::Type::Directional)
            {
                light["position"] = vec3(p.position);
                if (p.range > 0.0f)
                    light["range"] = number(p.range);
            }
            if (p.type != PunctualLight::Type::Point)
                light["direction"] = vec3(p.direction);
            if (p.type == PunctualLight::Type::Spot)
            {
                light["innerConeAngle"] = number(p.inner_cone);
                light["outerConeAngle"] = number(p.outer_cone);
            }
            if (l.angular_diameter_degrees > 0.0f)
                light["angularDiameter"] = number(l.angular_diameter_degrees);
            lights.push_back(Value(light));
        }
        ext["lights"] = Value(lights);
    }
    // Reflection probes: each one's centre, influence box and parabolic maps (the mirror map's level 0, the
    // glossy maps and the diffuse map), float32 RGB as the asset holds them.
    if (!asset.reflections.empty())
    {
        auto parabolic = [&](const math::ParabolicImage& image)
        {
            Value::Object map;
            map["size"] = Value(int(image.size));
            map["extent"] = number(image.extent);
            map["bufferView"] = Value(b.view(image.rgb.data(), image.rgb.size() * sizeof(float), 0));
            return map;
        };
        Value::Array probes;
        for (const ReflectionProbe& r : asset.reflections)
        {
            Value::Object probe;
            probe["centre"] = vec3(r.centre);
            probe["boxMin"] = vec3(r.box_min);
            probe["boxMax"] = vec3(r.box_max);
            probe["mirror"] = Value(parabolic(r.maps.mirror.at(0)));
            Value::Array glossy;
            for (size_t g = 0; g < r.maps.glossy.size(); ++g)
            {
                Value::Object map = parabolic(r.maps.glossy[g]);
                map["exponent"] = number(r.maps.exponents[g]);
                glossy.push_back(Value(map));
            }
            if (!glossy.empty())
                probe["glossy"] = Value(glossy);
            probe["diffuse"] = Value(parabolic(r.maps.diffuse));
            probes.push_back(Value(probe));
        }
        ext["reflectionProbes"] = Value(probes);
    }
    m.extensions["HEMI_lightmaps"] = Value(ext);
    m.extensionsUsed.push_back("HEMI_lightmaps");
    summary.bytes = m.buffers[0].data.size();
    // Everything counted now (the mesh, images, probes): a .glb's chunk lengths are 32-bit, and tinygltf
    // would cut them silently.
    if (summary.bytes > (uint64_t(1) << 32) - (uint64_t(1) << 26))
        throw std::invalid_argument(cannot + "the file's binary data would take " +
                                    std::to_string(summary.bytes >> 20) +
                                    " MiB, more than one glTF buffer holds (4 GiB); store fewer outputs");
    b.write(path);
    return summary;
}

} // namespace hemi::io
