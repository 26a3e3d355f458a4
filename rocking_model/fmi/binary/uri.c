#include "uri.h"

#include <stdio.h>
#include <string.h>

static int hex(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

static int starts_with_nocase(const char *s, const char *prefix) {
    for (; *prefix; s++, prefix++) {
        char a = *s, b = *prefix;
        if (a >= 'A' && a <= 'Z') a = (char)(a - 'A' + 'a');
        if (a != b) return 0;
    }
    return 1;
}

int uri_to_path(const char *uri, char *path, size_t size, char *why, size_t why_size) {
    if (!uri) {
        snprintf(why, why_size, "fmuResourceLocation is NULL; expected a file URI (file:///path/to/resources)");
        return -1;
    }
    if (!starts_with_nocase(uri, "file:")) {
        snprintf(why, why_size, "fmuResourceLocation \"%.200s\" is not a file URI; expected file:///path, "
                 "file:/path or file://localhost/path", uri);
        return -1;
    }
    const char *p = uri + 5;
    if (p[0] == '/' && p[1] == '/') {           /* an authority: empty or localhost */
        p += 2;
        if (starts_with_nocase(p, "localhost/")) {
            p += 9;
        } else if (p[0] != '/') {
            snprintf(why, why_size, "fmuResourceLocation \"%.200s\" names a remote host; only local files "
                     "(file:///path or file://localhost/path) are supported", uri);
            return -1;
        }
    } else if (p[0] != '/') {
        snprintf(why, why_size, "fmuResourceLocation \"%.200s\" is not an absolute file URI", uri);
        return -1;
    }
#ifdef _WIN32
    /* file:///C:/dir -> C:/dir */
    if (p[0] == '/' && ((p[1] >= 'A' && p[1] <= 'Z') || (p[1] >= 'a' && p[1] <= 'z')) && (p[2] == ':' || p[2] == '|'))
        p++;
#endif
    size_t n = 0;
    for (; *p; p++) {
        char c = *p;
        /* '#' and '?' are kept as characters: importers that build the URI by hand leave them unescaped,
         * and a resource location has no query or fragment */
        if (c == '%') {
            int hi = hex(p[1]), lo = hi < 0 ? -1 : hex(p[2]);
            if (hi < 0 || lo < 0) {
                snprintf(why, why_size, "fmuResourceLocation \"%.200s\" has an invalid escape (a '%%' must be "
                         "followed by two hexadecimal digits)", uri);
                return -1;
            }
            c = (char)(hi * 16 + lo);
            if (c == '\0') {
                snprintf(why, why_size, "fmuResourceLocation \"%.200s\" contains an escaped NUL (%%00)", uri);
                return -1;
            }
            p += 2;
        }
        if (n + 1 >= size) {
            snprintf(why, why_size, "fmuResourceLocation is longer than %zu bytes", size - 1);
            return -1;
        }
        path[n++] = c;
    }
    while (n > 1 && (path[n - 1] == '/' || path[n - 1] == '\\')) n--;
    path[n] = '\0';
    if (n == 0) {
        snprintf(why, why_size, "fmuResourceLocation \"%.200s\" has no path", uri);
        return -1;
    }
    return 0;
}
