// Device creation, selection, adoption of a host engine's device, and error reporting.
#include "../gpu_fixture.h"
#include "../host_vulkan.h"
#include "../vulkan_calls.h"

#include <hemi/gpu/commands.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/upload.h>
#include <hemi/gpu/vk_check.h>
#include <hemi/io/image.h>
#include <hemi/io/mesh.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/scene/gpu_mesh.h>
#include <hemi/render/transfer.h>

#include <cstdlib>
#include <cstring>

namespace
{

class DeviceTest : public hemi::test::GpuTest
{
};

} // namespace

TEST_F(DeviceTest, SelectsLavapipeByName)
{
    EXPECT_NE(std::string(hemi::test::device().name()).find("llvmpipe"), std::string::npos)
        << hemi::test::device().name();
    EXPECT_TRUE(hemi::test::device().owns_device());
    EXPECT_GT(hemi::test::device().timestamp_period_ns(), 0.0);
}

TEST(DeviceSelection, UnknownSelectorNamesTheDevices)
{
    hemi::gpu::DeviceDesc desc;
    desc.device_selector = "no-such-gpu";
    desc.validation = false;
    try
    {
        hemi::gpu::Device d(desc);
        FAIL() << "a device was created for a selector that matches nothing";
    }
    catch (const std::runtime_error& e)
    {
        std::string what = e.what();
        EXPECT_NE(what.find("no-such-gpu"), std::string::npos) << what;
        EXPECT_NE(what.find("llvmpipe"), std::string::npos) << what;
    }
}

TEST(VulkanError, NamesTheCallTheResultAndThePlace)
{
    try
    {
        HEMI_VK_CHECK(VK_ERROR_OUT_OF_DEVICE_MEMORY);
        FAIL();
    }
    catch (const hemi::gpu::VulkanError& e)
    {
        EXPECT_EQ(e.result(), VK_ERROR_OUT_OF_DEVICE_MEMORY);
        std::string what = e.what();
        EXPECT_NE(what.find("VK_ERROR_OUT_OF_DEVICE_MEMORY"), std::string::npos) << what;
        EXPECT_NE(what.find("device_test.cpp:"), std::string::npos) << what;
    }
    EXPECT_EQ(hemi::gpu::result_name(VK_ERROR_DEVICE_LOST), "VK_ERROR_DEVICE_LOST");
    EXPECT_EQ(hemi::gpu::result_name(VkResult(-12345)), "VK_RESULT(-12345)");
}

TEST_F(DeviceTest, BuffersRoundTripAndRejectOutOfRangeAccess)
{
    auto& dev = hemi::test::device();
    hemi::gpu::Buffer b = hemi::gpu::create_buffer(dev, {256, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
    std::vector<uint32_t> in(64), out(64);
    for (uint32_t i = 0; i < 64; ++i)
        in[i] = i * 2654435761u;
    hemi::gpu::write_buffer(dev, b, in.data(), 256);
    hemi::gpu::read_buffer(dev, b, out.data(), 256);
    EXPECT_EQ(in, out);
    EXPECT_THROW(hemi::gpu::write_buffer(dev, b, in.data(), 200, 100), std::out_of_range);
    EXPECT_THROW(hemi::gpu::create_buffer(dev, {0, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT}),
                 std::invalid_argument);
}

// A host engine creates its own instance (with its own validation messenger) and device, hands them to
// hemi, runs hemi work on them, destroys hemi's Device, and then destroys its objects itself: hemi must
// neither destroy the host's objects nor leak its own (the host instance's object tracker reports leaks).
TEST_F(DeviceTest, AdoptsAHostEngineDevice)
{
    hemi::test::HostVulkan host;
    ASSERT_NE(host.queue, VK_NULL_HANDLE);
    VkInstance instance = host.instance;
    VkPhysicalDevice pd = host.pd;
    VkDevice vk_device = host.vk_device;
    VkQueue queue = host.queue;

    {
        hemi::gpu::Device adopted(hemi::gpu::ExternalDevice{instance, pd, vk_device, queue, 0, {}});
        EXPECT_FALSE(adopted.owns_device());
        std::vector<float> t(50 * 4 * 9);
        for (size_t i = 0; i < t.size(); ++i)
            t[i] = float(i % 7) - 3.0f;
        hemi::render::TransferMatrices m(50, 4, 9, t);
        hemi::render::TransferPass pass(adopted, m);
        std::vector<glm::vec3> light(9, glm::vec3(0.0f));
        light[2] = glm::vec3(1.0f);
        pass.run(light);
        std::vector<float> c = pass.read_coefficients();
        EXPECT_EQ(c[(49 * 4 + 3) * 4 + 0], t[(49 * 4 + 3) * 9 + 2]);
    }
    // Still alive and usable after hemi let go.
    EXPECT_EQ(vkDeviceWaitIdle(vk_device), VK_SUCCESS);
}

// Issue 42: a Device's calls go through its own entry points, as VmaVulkanFunctions are an allocator's. Two
// Devices on two instances (an engine's, through a vkGetInstanceProcAddr that counts its calls, and a second
// one, as a tool inside the editor would make, through the loader's own), with the test's headless Device
// alive too: each reaches only its own instance, also after another one is made or destroyed. With process-
// wide entry points the second Device re-pointed every call of the first to its own instance (0 counted).
TEST_F(DeviceTest, TwoDevicesOnTwoInstancesEachReachOnlyTheirOwn)
{
    hemi::test::HostVulkan engine, tool;
    ASSERT_NE(engine.queue, VK_NULL_HANDLE);
    ASSERT_NE(tool.queue, VK_NULL_HANDLE);
    hemi::test::VulkanCalls& calls = hemi::test::vulkan_calls();
    auto nothing = [](VkCommandBuffer) {};
    hemi::gpu::Device a(engine.external(hemi::test::counting_proc_addr));
    {
        hemi::gpu::Device b(tool.external());
        calls.reset();
        hemi::gpu::one_shot(a, nothing);
        EXPECT_EQ(calls.submits, 1u)
            << "the engine's Device submitted through another instance's entry points";
        EXPECT_EQ(calls.fence_waits, 1u);
        calls.reset();
        hemi::gpu::one_shot(b, nothing);
        hemi::gpu::one_shot(hemi::test::device(), nothing);
        EXPECT_EQ(calls.submits, 0u) << "another Device's submit went through the engine's entry points";
    }
    calls.reset();
    hemi::gpu::one_shot(a, nothing);
    EXPECT_EQ(calls.submits, 1u) << "after the second Device was destroyed";
    // A Device made later over the engine's own device takes its calls while it lives.
    {
        hemi::gpu::Device again(engine.external());
        calls.reset();
        hemi::gpu::one_shot(again, nothing);
        EXPECT_EQ(calls.submits, 0u);
    }
    calls.reset();
    hemi::gpu::one_shot(a, nothing);
    EXPECT_EQ(calls.submits, 1u) << "after a second Device over the same VkDevice was destroyed";
}

// hemi names its Vulkan objects for debuggers (RenderDoc, the validation layer's messages) when the host's
// instance has VK_EXT_debug_utils and says so (ExternalDevice::debug_utils), and names nothing otherwise (the
// extension may not be enabled). Seen through the host's own vkGetInstanceProcAddr, which hands hemi a
// vkSetDebugUtilsObjectNameEXT that records each name and passes it on to the layer.
namespace
{
std::vector<std::pair<VkObjectType, std::string>> g_names;
PFN_vkSetDebugUtilsObjectNameEXT g_set_name = nullptr;

VKAPI_ATTR VkResult VKAPI_CALL record_name(VkDevice device, const VkDebugUtilsObjectNameInfoEXT* info)
{
    g_names.emplace_back(info->objectType, info->pObjectName);
    return g_set_name(device, info);
}

VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL recording_proc_addr(VkInstance instance, const char* name)
{
    if (std::strcmp(name, "vkSetDebugUtilsObjectNameEXT") == 0)
    {
        g_set_name =
            reinterpret_cast<PFN_vkSetDebugUtilsObjectNameEXT>(vkGetInstanceProcAddr(instance, name));
        return reinterpret_cast<PFN_vkVoidFunction>(&record_name);
    }
    return vkGetInstanceProcAddr(instance, name);
}
} // namespace

TEST_F(DeviceTest, NamesItsObjectsWhenTheHostHasDebugUtils)
{
    hemi::test::HostVulkan host;
    ASSERT_NE(host.queue, VK_NULL_HANDLE);
    for (bool debug_utils : {true, false})
    {
        g_names.clear();
        hemi::gpu::ExternalDevice e{host.instance, host.pd, host.vk_device, host.queue, 0, {}};
        e.get_instance_proc_addr = recording_proc_addr;
        e.debug_utils = debug_utils;
        {
            hemi::gpu::Device adopted(e);
            hemi::gpu::UploadBatch upload(adopted);
            const hemi::render::GpuMesh mesh(adopted, hemi::io::make_uv_sphere(1.0f, 8, 4), upload);
            hemi::io::Material material;
            material.base_color.image = 0;
            const hemi::io::EncodedImage image{"bricks", "image/png",
                                               hemi::io::encode_png({1, 1, {10, 20, 30, 255}})};
            const hemi::render::TextureSet textures(
                adopted, std::span<const hemi::io::EncodedImage>(&image, 1),
                std::span<const hemi::io::Material>(&material, 1), upload);
            upload.submit_and_wait();
            const hemi::render::TransferMatrices m(4, 4, 9, std::vector<float>(4 * 4 * 9, 0.5f));
            const hemi::render::TransferPass pass(adopted, m);
        }
        if (!debug_utils)
        {
            EXPECT_TRUE(g_names.empty())
                << g_names.size() << " names without debug utils, e.g. " << g_names.front().second;
            continue;
        }
        auto named = [&](VkObjectType type, const std::string& name)
        {
            for (const auto& [t, n] : g_names)
                if (t == type && n == name)
                    return true;
            return false;
        };
        EXPECT_TRUE(named(VK_OBJECT_TYPE_BUFFER, "hemi mesh vertices"));
        EXPECT_TRUE(named(VK_OBJECT_TYPE_BUFFER, "hemi mesh indices"));
        EXPECT_TRUE(named(VK_OBJECT_TYPE_IMAGE, "hemi texture 'bricks' (sRGB)"));
        EXPECT_TRUE(named(VK_OBJECT_TYPE_BUFFER, "hemi PRT transfer matrices"));
        EXPECT_TRUE(named(VK_OBJECT_TYPE_BUFFER, "hemi PRT coefficients"));
        EXPECT_TRUE(named(VK_OBJECT_TYPE_PIPELINE, "hemi PRT transfer pass"));
    }
}

// The host instance's messenger above drops the loader's notes and keeps the layer's findings: what
// AdoptsAHostEngineDevice needs to pass with VK_LOADER_LAYERS_ENABLE=*validation* set and still fail on a
// validation message. Messages made up here, shaped as the loader and the layer send them.
TEST(DeviceValidation, HostMessengerDropsLoaderNotesOnly)
{
    hemi::test::validation_log().take();
    VkDebugUtilsMessengerCallbackDataEXT loader{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CALLBACK_DATA_EXT};
    loader.pMessageIdName = "Loader Message";
    loader.pMessage =
        "Layer VK_LAYER_KHRONOS_validation forced enabled due to env var 'VK_LOADER_LAYERS_ENABLE'";
    VkDebugUtilsMessengerCallbackDataEXT layer{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CALLBACK_DATA_EXT};
    layer.pMessageIdName = "VUID-VkBufferCreateInfo-usage-requiredbitmask";
    layer.pMessage = "usage must not be 0";
    const auto general = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT;
    const auto validation = VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
    const auto warning = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT;
    EXPECT_TRUE(hemi::gpu::is_loader_message(general, &loader));
    EXPECT_FALSE(hemi::gpu::is_loader_message(validation, &loader))
        << "the loader sends general messages only";
    EXPECT_FALSE(hemi::gpu::is_loader_message(general, &layer));
    EXPECT_FALSE(hemi::gpu::is_loader_message(validation, &layer));
    EXPECT_FALSE(hemi::gpu::is_loader_message(general, nullptr));

    hemi::test::host_messenger(warning, general, &loader, nullptr);
    EXPECT_TRUE(hemi::test::validation_log().take().empty()) << "a loader note failed the host's test";
    hemi::test::host_messenger(warning, validation, &layer, nullptr);
    hemi::test::host_messenger(warning, general, &layer, nullptr);
    const std::vector<std::string> kept = hemi::test::validation_log().take();
    ASSERT_EQ(kept.size(), 2u) << "the layer's messages must still fail the host's test";
    EXPECT_NE(kept[0].find("usage must not be 0"), std::string::npos) << kept[0];
}

TEST(DeviceAdoption, RejectsIncompleteHandles)
{
    EXPECT_THROW(hemi::gpu::Device(hemi::gpu::ExternalDevice{}), std::invalid_argument);
}

// The fixture's check is only worth something if the layer is really on and reporting: provoke one error.
TEST_F(DeviceTest, ValidationLayerReportsMisuse)
{
    auto& dev = hemi::test::device();
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = 16;
    info.usage = 0; // VUID-VkBufferCreateInfo-usage-requiredbitmask
    VkBuffer buffer = VK_NULL_HANDLE;
    VkResult r = vkCreateBuffer(dev.device(), &info, nullptr, &buffer);
    if (r == VK_SUCCESS)
        vkDestroyBuffer(dev.device(), buffer, nullptr);
    std::vector<std::string> messages = hemi::test::validation_log().take();
    ASSERT_FALSE(messages.empty()) << "the validation layer did not report an invalid VkBufferCreateInfo";
    EXPECT_NE(messages[0].find("usage"), std::string::npos) << messages[0];
}

// Forcing the layer on through the loader (VK_LOADER_LAYERS_ENABLE, a common way to debug) makes the loader
// say so through the messenger: that note is logged as what it is (Info, not a validation message) and
// counts as no validation problem, while the layer itself stays live.
TEST(DeviceValidation, LoaderNotesAreNotValidationMessages)
{
    setenv("VK_LOADER_LAYERS_ENABLE", "*validation*", 1);
    std::vector<std::pair<bool, std::string>> messages;
    {
        hemi::gpu::DeviceDesc desc;
        desc.device_selector = "llvmpipe";
        desc.validation = true;
        desc.log = [&](hemi::gpu::LogLevel, bool validation, std::string_view m)
        { messages.emplace_back(validation, std::string(m)); };
        hemi::gpu::Device device(desc);
        hemi::gpu::Buffer b = hemi::gpu::create_buffer(device, {256, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
        EXPECT_EQ(device.validation_messages(), 0u);
    }
    unsetenv("VK_LOADER_LAYERS_ENABLE");
    bool loader_note = false;
    for (const auto& [validation, m] : messages)
    {
        EXPECT_FALSE(validation) << "counted as a validation message: " << m;
        loader_note = loader_note || m.find("VK_LOADER_LAYERS_ENABLE") != std::string::npos;
    }
    EXPECT_TRUE(loader_note) << "the loader said nothing: this test no longer exercises its note";
}
