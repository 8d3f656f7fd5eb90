/* Preloaded into the sanitizer test run (scripts/sanitize.sh): opens Mesa's lavapipe
 * Vulkan driver with RTLD_NODELETE so it stays mapped after the Vulkan loader dlclose()s
 * it at vkDestroyInstance. Without this, LeakSanitizer's report at exit shows the driver's
 * frames as "<unknown module>" and no suppression (lsan.supp) can name the library that
 * owns them. Nothing else changes: the loader still opens and uses the driver itself. */
#include <dlfcn.h>

__attribute__((constructor)) static void skycal_keep_lavapipe_loaded(void) {
  dlopen("libvulkan_lvp.so", RTLD_NOW | RTLD_NODELETE);
}
