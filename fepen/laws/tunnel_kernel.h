/* The tunnel's state as Python shares it (fepen/laws/tunnel.py reads these enums with fepen.native.c_enums):
 * one flat array of doubles, a header of T_HEADER numbers, then the stations, each T_STATION + S numbers
 * (tunnel_kernel.c, which target_kernel.c includes; the tunnel has no function of its own that Python calls). */
#ifndef FEPEN_TUNNEL_KERNEL_H
#define FEPEN_TUNNEL_KERNEL_H

enum { T_M /* stations recorded */, T_CAP /* room for stations */, T_S /* sectors */, T_SPACING /* m */,
       T_XI_SH /* the shoulder's distance behind the tip, body frame (m) */, T_A0 /* its radius (m) */,
       T_RESERVED,
       T_COMMIT /* 1: this call records the station and the wall's expansion (a step's first stage) */,
       T_CS /* the shoulder's centre now (3) */, T_TS = T_CS + 3 /* the axis now, tail to nose (3) */,
       T_FACE = T_TS + 3 /* the face's y: the shoulder is in once below it */, T_HEADER = 16 };
enum { T_C /* centre (3) */, T_T = 3 /* direction (3) */, T_ARC = 6 /* arc length */,
       T_AMIN = 7 /* the smallest of its radii (a lower bound of it: ranks that widened it apart took each one's
                     largest, tunnel_kernel.c) */,
       T_STATION = 8 /* then a[S] */ };

#endif
