// The headless Vulkan context (vff/vk/context.h): instance, validation layer and debug messenger,
// device choice, queue, command pool and one-shot submissions.
#include "vff/vk/context.h"

#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "vk_objects.h"

namespace vff::vk {
namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

const char* resultName(VkResult r) {
  switch (r) {
    case VK_SUCCESS:
      return "VK_SUCCESS";
    case VK_ERROR_OUT_OF_HOST_MEMORY:
      return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY:
      return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED:
      return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST:
      return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_LAYER_NOT_PRESENT:
      return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT:
      return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT:
      return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER:
      return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_FORMAT_NOT_SUPPORTED:
      return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    default:
      return "VkResult";
  }
}

bool hasLayer(const char* name) {
  uint32_t n = 0;
  if (vkEnumerateInstanceLayerProperties(&n, nullptr) != VK_SUCCESS) return false;
  std::vector<VkLayerProperties> layers(n);
  if (vkEnumerateInstanceLayerProperties(&n, layers.data()) != VK_SUCCESS) return false;
  for (const auto& l : layers)
    if (std::strcmp(l.layerName, name) == 0) return true;
  return false;
}

// Whether the instance offers the extension, by itself or through `layer`.
bool hasInstanceExtension(const char* name, const char* layer) {
  for (const char* from : {static_cast<const char*>(nullptr), layer}) {
    uint32_t n = 0;
    if (vkEnumerateInstanceExtensionProperties(from, &n, nullptr) != VK_SUCCESS) continue;
    std::vector<VkExtensionProperties> ext(n);
    if (vkEnumerateInstanceExtensionProperties(from, &n, ext.data()) != VK_SUCCESS) continue;
    for (const auto& e : ext)
      if (std::strcmp(e.extensionName, name) == 0) return true;
  }
  return false;
}

bool validationRequested(const ContextOptions& o) {
  const char* env = std::getenv("VFF_VK_VALIDATION");
  return o.validation || (env && std::strcmp(env, "1") == 0);
}

// Lower is better: the device types in the order the options prefer them.
int rank(VkPhysicalDeviceType t, bool preferCpu) {
  if (preferCpu && t == VK_PHYSICAL_DEVICE_TYPE_CPU) return 0;
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return 1;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return 2;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return 3;
    default:
      return 4;
  }
}

uint32_t computeFamily(VkPhysicalDevice pd) {
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> fam(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, fam.data());
  for (uint32_t i = 0; i < n; ++i)
    if (fam[i].queueFlags & VK_QUEUE_COMPUTE_BIT) return i;
  return UINT32_MAX;
}

}  // namespace

Error vkError(VkResult r, const char* what) {
  const bool oom = r == VK_ERROR_OUT_OF_HOST_MEMORY || r == VK_ERROR_OUT_OF_DEVICE_MEMORY;
  return makeError(oom ? Code::kOutOfMemory : Code::kUnsupported,
                   std::string(what) + " failed: " + resultName(r) + " (" + std::to_string(int(r)) + ")");
}

struct Context::State {
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties props{};
  VkPhysicalDeviceMemoryProperties memory{};
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t family = 0;
  VkCommandPool pool = VK_NULL_HANDLE;
  bool validation = false;
  std::string note;
  uint32_t errors = 0, warnings = 0;
  std::string log;

  ~State() {
    if (device) {
      vkDeviceWaitIdle(device);
      if (pool) vkDestroyCommandPool(device, pool, nullptr);
      vkDestroyDevice(device, nullptr);
    }
    if (messenger) {
      auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
      if (destroy) destroy(instance, messenger, nullptr);
    }
    if (instance) vkDestroyInstance(instance, nullptr);
  }
};

namespace {

VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                         VkDebugUtilsMessageTypeFlagsEXT,
                                         const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* s = static_cast<Context::State*>(user);
  const bool error = (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) != 0;
  ++(error ? s->errors : s->warnings);
  s->log += std::string(error ? "error: " : "warning: ") + (data && data->pMessage ? data->pMessage : "") + "\n";
  return VK_FALSE;  // never abort the call: the caller reads the counts
}

}  // namespace

Context::Context() = default;
Context::Context(Context&&) noexcept = default;
Context& Context::operator=(Context&&) noexcept = default;
Context::~Context() = default;

namespace {

Status createInstance(Context::State& s, const ContextOptions& options);
Status chooseDevice(Context::State& s, bool preferCpu);

}  // namespace

Result<Context> Context::create(const ContextOptions& options) {
  Context c;
  c.s_ = std::make_unique<State>();
  if (Status st = createInstance(*c.s_, options); !st) return st.error();
  if (Status st = chooseDevice(*c.s_, options.preferCpu); !st) return st.error();
  return c;
}

namespace {

Status createInstance(Context::State& s, const ContextOptions& options) {
  auto app = detail::vkStruct<VkApplicationInfo>(VK_STRUCTURE_TYPE_APPLICATION_INFO);
  app.pApplicationName = "vff";
  app.apiVersion = VK_API_VERSION_1_1;
  std::vector<const char*> layers, extensions;
  if (validationRequested(options)) {
    if (!hasLayer(kValidationLayer)) {
      s.note = std::string(kValidationLayer) + " is not installed (Debian: vulkan-validationlayers)";
    } else if (!hasInstanceExtension(VK_EXT_DEBUG_UTILS_EXTENSION_NAME, kValidationLayer)) {
      s.note = "VK_EXT_debug_utils is not available";
    } else {
      layers.push_back(kValidationLayer);
      extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
      s.validation = true;
    }
  }
  auto mi =
      detail::vkStruct<VkDebugUtilsMessengerCreateInfoEXT>(VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT);
  mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                   VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  mi.pfnUserCallback = onMessage;
  mi.pUserData = &s;
  auto ci = detail::vkStruct<VkInstanceCreateInfo>(VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO);
  // Chained, the messenger also hears vkCreateInstance and vkDestroyInstance themselves.
  if (s.validation) ci.pNext = &mi;
  ci.pApplicationInfo = &app;
  ci.enabledLayerCount = uint32_t(layers.size());
  ci.ppEnabledLayerNames = layers.data();
  ci.enabledExtensionCount = uint32_t(extensions.size());
  ci.ppEnabledExtensionNames = extensions.data();
  if (VkResult r = vkCreateInstance(&ci, nullptr, &s.instance); r != VK_SUCCESS) {
    s.instance = VK_NULL_HANDLE;
    return vkError(r, "vkCreateInstance");
  }
  if (!s.validation) return {};
  auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
      vkGetInstanceProcAddr(s.instance, "vkCreateDebugUtilsMessengerEXT"));
  if (!create) return makeError(Code::kUnsupported, "vkCreateDebugUtilsMessengerEXT is not available");
  if (VkResult r = create(s.instance, &mi, nullptr, &s.messenger); r != VK_SUCCESS) {
    s.messenger = VK_NULL_HANDLE;
    return vkError(r, "vkCreateDebugUtilsMessengerEXT");
  }
  return {};
}

Status chooseDevice(Context::State& s, bool preferCpu) {
  uint32_t n = 0;
  if (VkResult r = vkEnumeratePhysicalDevices(s.instance, &n, nullptr); r != VK_SUCCESS)
    return vkError(r, "vkEnumeratePhysicalDevices");
  std::vector<VkPhysicalDevice> devices(n);
  vkEnumeratePhysicalDevices(s.instance, &n, devices.data());
  int best = 99;
  for (VkPhysicalDevice pd : devices) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(pd, &p);
    const int r = rank(p.deviceType, preferCpu);
    if (r < best && computeFamily(pd) != UINT32_MAX) {
      best = r;
      s.physical = pd;
      s.props = p;
    }
  }
  if (!s.physical) return makeError(Code::kUnsupported, "no Vulkan device with a compute queue");
  vkGetPhysicalDeviceMemoryProperties(s.physical, &s.memory);
  s.family = computeFamily(s.physical);
  const float priority = 1.0f;
  auto qi = detail::vkStruct<VkDeviceQueueCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO);
  qi.queueFamilyIndex = s.family;
  qi.queueCount = 1;
  qi.pQueuePriorities = &priority;
  auto di = detail::vkStruct<VkDeviceCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO);
  di.queueCreateInfoCount = 1;
  di.pQueueCreateInfos = &qi;
  if (VkResult r = vkCreateDevice(s.physical, &di, nullptr, &s.device); r != VK_SUCCESS) {
    s.device = VK_NULL_HANDLE;
    return vkError(r, "vkCreateDevice");
  }
  vkGetDeviceQueue(s.device, s.family, 0, &s.queue);
  auto pi = detail::vkStruct<VkCommandPoolCreateInfo>(VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO);
  pi.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
  pi.queueFamilyIndex = s.family;
  if (VkResult r = vkCreateCommandPool(s.device, &pi, nullptr, &s.pool); r != VK_SUCCESS) {
    s.pool = VK_NULL_HANDLE;
    return vkError(r, "vkCreateCommandPool");
  }
  return {};
}

}  // namespace

VkInstance Context::instance() const noexcept {
  return s_ ? s_->instance : VK_NULL_HANDLE;
}
VkPhysicalDevice Context::physicalDevice() const noexcept {
  return s_ ? s_->physical : VK_NULL_HANDLE;
}
VkDevice Context::device() const noexcept {
  return s_ ? s_->device : VK_NULL_HANDLE;
}
VkQueue Context::queue() const noexcept {
  return s_ ? s_->queue : VK_NULL_HANDLE;
}
uint32_t Context::queueFamily() const noexcept {
  return s_ ? s_->family : 0;
}
const VkPhysicalDeviceProperties& Context::properties() const noexcept {
  return s_->props;
}
std::string Context::deviceName() const {
  return s_ ? std::string(s_->props.deviceName) : std::string();
}
bool Context::validationEnabled() const noexcept {
  return s_ && s_->validation;
}
const std::string& Context::validationNote() const noexcept {
  return s_->note;
}
uint32_t Context::validationErrors() const noexcept {
  return s_ ? s_->errors : 0;
}
uint32_t Context::validationWarnings() const noexcept {
  return s_ ? s_->warnings : 0;
}
const std::string& Context::validationLog() const noexcept {
  return s_->log;
}

uint32_t Context::memoryType(uint32_t typeBits, VkMemoryPropertyFlags flags) const noexcept {
  for (uint32_t i = 0; i < s_->memory.memoryTypeCount; ++i)
    if ((typeBits & (1u << i)) && (s_->memory.memoryTypes[i].propertyFlags & flags) == flags) return i;
  return UINT32_MAX;
}

Status Context::submitAndWait(const std::function<void(VkCommandBuffer)>& record) const {
  auto ai = detail::vkStruct<VkCommandBufferAllocateInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO);
  ai.commandPool = s_->pool;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cb = VK_NULL_HANDLE;
  if (VkResult r = vkAllocateCommandBuffers(s_->device, &ai, &cb); r != VK_SUCCESS)
    return vkError(r, "vkAllocateCommandBuffers");
  auto bi = detail::vkStruct<VkCommandBufferBeginInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO);
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VkResult r = vkBeginCommandBuffer(cb, &bi);
  if (r == VK_SUCCESS) {
    record(cb);
    r = vkEndCommandBuffer(cb);
  }
  VkFence fence = VK_NULL_HANDLE;
  if (r == VK_SUCCESS) {
    auto fi = detail::vkStruct<VkFenceCreateInfo>(VK_STRUCTURE_TYPE_FENCE_CREATE_INFO);
    r = vkCreateFence(s_->device, &fi, nullptr, &fence);
  }
  if (r == VK_SUCCESS) {
    auto si = detail::vkStruct<VkSubmitInfo>(VK_STRUCTURE_TYPE_SUBMIT_INFO);
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cb;
    r = vkQueueSubmit(s_->queue, 1, &si, fence);
    if (r == VK_SUCCESS) r = vkWaitForFences(s_->device, 1, &fence, VK_TRUE, UINT64_MAX);
  }
  if (fence) vkDestroyFence(s_->device, fence, nullptr);
  vkFreeCommandBuffers(s_->device, s_->pool, 1, &cb);
  if (r != VK_SUCCESS) return vkError(r, "submitting a command buffer");
  return {};
}

}  // namespace vff::vk
