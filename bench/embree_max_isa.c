/* Preloaded by bench/side_by_side.py --max-isa avx2 (LD_PRELOAD): Mitsuba's Embree device is
 * created with "max_isa=$EMBREE_MAX_ISA" added to its configuration, so that Embree runs
 * its AVX2 kernels on an AVX-512 host. Mitsuba's Embree has its API in the `mitsuba`
 * namespace, hence the C++ name; its library is loaded privately with the Python module, so
 * the real function is looked up in it by name. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>

typedef void *(*new_device_fn)(const char *);

void *_ZN7mitsuba12rtcNewDeviceEPKc(const char *cfg) {
    void *lib = dlopen("libembree3.so", RTLD_NOW | RTLD_NOLOAD);
    new_device_fn real = lib ? (new_device_fn)dlsym(lib, "_ZN7mitsuba12rtcNewDeviceEPKc") : NULL;
    if (!real) {
        fprintf(stderr, "embree_max_isa: Mitsuba's rtcNewDevice not found\n");
        abort();
    }
    const char *isa = getenv("EMBREE_MAX_ISA");
    static char buf[1024];
    snprintf(buf, sizeof buf, "%s%smax_isa=%s", cfg ? cfg : "", cfg && *cfg ? "," : "",
             isa && *isa ? isa : "avx2");
    return real(buf);
}
