/* fmuResourceLocation (an RFC 3986 file URI) to a local path. */
#ifndef FMI_BINARY_URI_H
#define FMI_BINARY_URI_H

#include <stddef.h>

/* Decode `uri` into `path` (capacity `size`, NUL-terminated, no trailing separator).
 * Accepted forms: file:///abs/path, file:/abs/path, file://localhost/abs/path (and, on Windows,
 * file:///C:/dir). Every %XX escape is decoded (bytes, so UTF-8 names come out as UTF-8).
 * Returns 0 on success; otherwise writes the reason into `why` (capacity `why_size`) and returns -1. */
int uri_to_path(const char *uri, char *path, size_t size, char *why, size_t why_size);

#endif
