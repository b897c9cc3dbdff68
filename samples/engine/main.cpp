// engine: hemi inside an engine's own frame. The engine owns the window (GLFW), the Vulkan instance and
// device (loaded with volk), the swapchain (FIFO, re-made on resize), two frames in flight and its render
// graph (the sun's shadow map, depth prepass, main pass with its own shaders, post pass); hemi supplies the
// baked data (a lightmapped level with an SSBump wall, a polished floor and a mixed sun's shadowmask, light
// probes, a PRT torus relit every frame, a Heidrich-Seidel glossy ball's parabolic maps), its depth and
// shadow pipelines, and the GLSL library the engine's shaders include. docs/integration.md walks through it.
//
//   engine [--assets DIR] [--size WxH] [--frames N] [--screenshot FILE] [--validation] [--baked-only]
//          [--basis auto|h6|h4] [--sun mixed|baked] [--shadow-distance D] [--no-coat] [--specular-only]
//          [--exposure E]
//          [--no-tonemap] [--fog D] [--camera EYE,TARGET] [--object-time T] [--resize-at N]
//
// With --frames it prints, for the last frame, where each probe-lit sphere is on screen and what the level's
// probes give it (tests/tools/engine_sample_test.cpp reads it).
//
// Keys: T next basis (H6 near / H4 far, H6, H4), W lighting only, S specular only, B baked lighting only, L
// the sun's shadow map on/off (off: the shadowmask alone), G the floor's GGX coat on/off, E pause the
// environment, O pause the objects, F fog, M tonemap, P screenshot (engine_NNN.png), Esc quit. Exit status 2
// when the validation layer reported anything (--validation).
#include "assets.h"
#include "context.h"
#include "renderer.h"

#include <hemi/io/atomic_file.h>

#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>

namespace
{

struct Input
{
    engine::Settings* settings;
    bool pause_env = false, pause_objects = false, screenshot = false, resized = false;
};

void on_key(GLFWwindow* window, int key, int, int action, int)
{
    if (action != GLFW_PRESS)
        return;
    auto* in = static_cast<Input*>(glfwGetWindowUserPointer(window));
    engine::Settings& s = *in->settings;
    switch (key)
    {
    case GLFW_KEY_ESCAPE:
        glfwSetWindowShouldClose(window, GLFW_TRUE);
        break;
    case GLFW_KEY_T:
        s.basis = (s.basis + 1) % 3;
        break;
    case GLFW_KEY_W:
        s.lighting_only = !s.lighting_only;
        break;
    case GLFW_KEY_S:
        s.specular_only = !s.specular_only;
        break;
    case GLFW_KEY_B:
        s.baked_only = !s.baked_only;
        break;
    case GLFW_KEY_L:
        s.shadow_map = !s.shadow_map;
        break;
    case GLFW_KEY_G:
        s.coat = !s.coat;
        break;
    case GLFW_KEY_E:
        in->pause_env = !in->pause_env;
        break;
    case GLFW_KEY_O:
        in->pause_objects = !in->pause_objects;
        break;
    case GLFW_KEY_F:
        s.fog = s.fog > 0.0f ? 0.0f : 0.02f;
        break;
    case GLFW_KEY_M:
        s.tonemap = !s.tonemap;
        break;
    case GLFW_KEY_P:
        in->screenshot = true;
        break;
    default:
        break;
    }
}

void on_resize(GLFWwindow* window, int, int)
{
    static_cast<Input*>(glfwGetWindowUserPointer(window))->resized = true;
}

// A number option's check: a finite value in [lo, hi] (CLI::Range lets NaN through).
CLI::Validator finite_in(double lo, double hi)
{
    return CLI::Validator(
        [lo, hi](std::string& value) -> std::string
        {
            char* end = nullptr;
            const double v = std::strtod(value.c_str(), &end);
            if (value.empty() || *end != '\0' || !std::isfinite(v) || v < lo || v > hi)
                return "'" + value + "' is not a finite number in [" + std::to_string(lo) + ", " +
                       std::to_string(hi) + "]";
            return {};
        },
        "finite number", "finite");
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{
        "engine: hemi's techniques in an engine's own frame (window, swapchain, render graph, shaders)"};
    std::string assets_dir = "engine_assets", size = "960x540", screenshot, basis = "auto", camera,
                sun = "mixed";
    int frames = 0, resize_at = -1;
    float object_time = 0.0f;
    bool validation = false, no_tonemap = false, no_coat = false;
    engine::Settings settings;
    app.add_option("--assets", assets_dir, "folder of the baked assets (baked there when missing)")
        ->capture_default_str();
    app.add_option("--size", size, "window size WIDTHxHEIGHT")->capture_default_str();
    app.add_option("--frames", frames, "draw N frames and exit (0: until the window closes)")
        ->check(CLI::Range(0, 1000000));
    app.add_option("--screenshot", screenshot, "with --frames: the last frame as this PNG");
    app.add_flag("--validation", validation,
                 "the Khronos validation layer with synchronisation validation; any message makes the exit "
                 "status 2");
    app.add_flag(
        "--baked-only", settings.baked_only,
        "the level alone in H4 (its SSBump wall in SSBump), lit by its lightmap and its mixed sun through "
        "the "
        "shadowmask alone, no coat, fog or tonemap: what `hemi-render engine_level.hemi --technique h4` "
        "draws from the same camera");
    app.add_option("--basis", basis, "the level's lightmap basis: auto (H6 near, H4 far), h6 or h4")
        ->check(CLI::IsMember({"auto", "h6", "h4"}))
        ->capture_default_str();
    app.add_option("--sun", sun,
                   "the level's sun: mixed (its bounces baked, its direct light at run time through the "
                   "shadowmask and the shadow map: shadows of moving objects, its exact highlight) or baked "
                   "(all of its light in the lightmap: the floor's highlight from the directional lightmap); "
                   "each is its own asset in --assets")
        ->check(CLI::IsMember({"mixed", "baked"}))
        ->capture_default_str();
    app.add_option("--shadow-distance", settings.shadow_distance,
                   "how far from the eye the sun's shadow map reaches (beyond it, the static shadows alone)")
        ->check(finite_in(0.0, 1000.0))
        ->capture_default_str();
    app.add_flag("--no-coat", no_coat, "no GGX coat on the polished floor (no specular)");
    app.add_flag("--specular-only", settings.specular_only,
                 "the coat's light alone: the directional lightmap's specular and the mixed sun's");
    app.add_option("--exposure", settings.exposure, "exposure before the tonemap (--baked-only: 1)")
        ->check(finite_in(1e-6, 1e6))
        ->capture_default_str();
    app.add_flag("--no-tonemap", no_tonemap, "clamp instead of the filmic tonemap");
    app.add_option("--fog", settings.fog, "fog density per unit of distance (0: none)")
        ->check(finite_in(0.0, 10.0))
        ->capture_default_str();
    app.add_option("--camera", camera,
                   "EYE,TARGET as x,y,z,x,y,z in world space (z up), as hemi-render's --camera takes it "
                   "(default -3.5,0.8,1.6,3,-0.6,0.9)");
    app.add_option("--object-time", object_time,
                   "start the moving objects this many seconds into their animation (where the spheres are)")
        ->check(finite_in(0.0, 1e6))
        ->capture_default_str();
    app.add_option("--resize-at", resize_at,
                   "resize the window to 3/4 of --size at this frame (tests resizing)");
    try
    {
        app.parse(argc, argv);
    }
    catch (const CLI::ParseError& e)
    {
        return app.exit(e) == 0 ? 0 : 1; // a usage error exits 1 (--help 0), as hemi's tools do
    }
    settings.tonemap = !no_tonemap;
    settings.coat = !no_coat;
    settings.basis = basis == "auto" ? 0 : basis == "h6" ? 1 : 2;

    try
    {
        unsigned w = 0, h = 0;
        char x = 0, rest = 0;
        if (std::sscanf(size.c_str(), "%u%c%u%c", &w, &x, &h, &rest) != 3 || x != 'x' || w < 64 || h < 64 ||
            w > 8192 || h > 8192)
            throw std::invalid_argument("--size expects WIDTHxHEIGHT (64 to 8192 each), got '" + size + "'");
        if (!camera.empty())
        {
            const std::optional<hemi::math::Camera> c = hemi::math::parse_camera(camera);
            if (!c)
                throw std::invalid_argument("--camera takes EYE,TARGET (six numbers), not 'auto'");
            settings.camera = *c;
        }
        if (!screenshot.empty() && frames == 0)
            throw std::invalid_argument("--screenshot needs --frames N (interactively, press P)");
        // The screenshot follows the tools' output rules, checked before the assets or a frame: a PNG, in a
        // folder it can be written to, and none of the assets (inputs) the sample reads from --assets.
        if (!screenshot.empty())
        {
            const std::filesystem::path shot(screenshot);
            if (shot.extension() != ".png")
                throw std::invalid_argument("--screenshot must end in .png, got '" + screenshot + "'");
            std::error_code ec;
            if (shot.filename().string().rfind("engine_", 0) == 0 &&
                std::filesystem::weakly_canonical(shot.parent_path().empty() ? "." : shot.parent_path(),
                                                  ec) == std::filesystem::weakly_canonical(assets_dir, ec))
                throw std::invalid_argument("--screenshot " + screenshot + " is in --assets " + assets_dir +
                                            " under an asset's name (engine_*): the screenshot would "
                                            "overwrite the sample's input");
            hemi::io::check_writable(shot);
        }

        const auto t0 = std::chrono::steady_clock::now();
        const hemi::samples::EngineAssets assets = hemi::samples::prepare_engine_assets(
            assets_dir, sun == "mixed",
            [](const std::string& line) { std::fprintf(stderr, "engine: %s\n", line.c_str()); });

        if (!glfwInit())
            throw std::runtime_error("GLFW cannot open a display (headless: run under xvfb-run)");
        glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
        GLFWwindow* window = glfwCreateWindow(int(w), int(h), "hemi engine sample", nullptr, nullptr);
        if (!window)
            throw std::runtime_error("GLFW could not create a window");
        Input input{&settings};
        glfwSetWindowUserPointer(window, &input);
        glfwSetKeyCallback(window, on_key);
        glfwSetFramebufferSizeCallback(window, on_resize);

        uint64_t messages = 0;
        int status = 0;
        {
            engine::Context context(window, validation);
            engine::Swapchain swapchain(context, window);
            engine::Renderer renderer(context, swapchain, assets);
            std::fprintf(stderr, "engine: ready in %.1f s (%ux%u, %s)\n",
                         std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                         swapchain.extent.width, swapchain.extent.height,
                         validation ? "validation on" : "no validation");

            // Headless runs step time by 1/60 s a frame, so the same frame number gives the same image.
            engine::FrameState state;
            state.object_time = object_time;
            auto last = std::chrono::steady_clock::now();
            double total_ms = 0.0;
            int timed = 0, shots = 0, drawn = 0;
            engine::FrameStats stats;
            for (int frame = 0; (frames == 0 || frame < frames) && !glfwWindowShouldClose(window); ++frame)
            {
                glfwPollEvents();
                if (frame == resize_at)
                    glfwSetWindowSize(window, int(w * 3 / 4), int(h * 3 / 4));
                if (input.resized)
                {
                    input.resized = false;
                    swapchain.recreate();
                }
                const auto now = std::chrono::steady_clock::now();
                const float dt = frames > 0 ? 1.0f / 60.0f : std::chrono::duration<float>(now - last).count();
                if (frame > 0)
                {
                    // Frame time: from one frame's start to the next (the first includes pipeline warm-up).
                    if (frame > 1)
                    {
                        total_ms += std::chrono::duration<double, std::milli>(now - last).count();
                        ++timed;
                    }
                    if (!input.pause_env)
                        state.env_time += dt;
                    if (!input.pause_objects)
                        state.object_time += dt;
                }
                last = now;
                std::string shot;
                if (frames > 0 && frame == frames - 1)
                    shot = screenshot;
                else if (input.screenshot)
                {
                    char name[32];
                    std::snprintf(name, sizeof name, "engine_%03d.png", shots++);
                    shot = name;
                }
                input.screenshot = false;
                stats = renderer.frame(settings, state, shot);
                ++drawn;
                if (!shot.empty())
                    std::fprintf(stderr, "engine: wrote %s\n", shot.c_str());
            }
            renderer.finish();
            messages = context.messages();
            // Where the last frame drew the probe-lit spheres, and what the probes give them.
            for (size_t i = 0; i < stats.spheres.size() && frames > 0; ++i)
            {
                const engine::SphereSeen& s = stats.spheres[i];
                std::printf(
                    "engine: sphere %zu at pixel (%.1f, %.1f), radius %.1f px%s; the probes give it %.3f, "
                    "%.2f of the sun\n",
                    i, s.centre.x, s.centre.y, s.radius, s.in_front ? "" : " (behind the eye)", s.light,
                    s.sun_share);
            }
            std::printf(
                "engine: %d frames at %ux%u, %.1f ms a frame (mean over %d), %u level draws, %u culled, "
                "%llu validation message(s)\n",
                drawn, swapchain.extent.width, swapchain.extent.height, timed > 0 ? total_ms / timed : 0.0,
                timed, stats.draws, stats.culled, (unsigned long long)messages);
            if (validation && messages > 0)
                status = 2;
        }
        glfwDestroyWindow(window);
        glfwTerminate();
        return status;
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "engine: %s\n", e.what());
        return 1;
    }
}
