// Work order of the ray-casting stages: the N x N texels are cut into 16 x 16 tiles (one TBB task
// each, disjoint outputs) and every tile into 4 x 4 packets (one 16-wide Embree packet:
// neighbouring texels, one direction, so the rays are coherent). Edge tiles of an N that is not a
// multiple of 16 hold partial packets.
#pragma once

#include <algorithm>
#include <array>

namespace clothbake::raycast {

class TexelBlocks {
 public:
  static constexpr int kTile = 16;
  static constexpr int kPacket = 4;

  explicit TexelBlocks(int resolution)
      : n_(resolution), tiles_per_side_((resolution + kTile - 1) / kTile) {}

  int tile_count() const { return tiles_per_side_ * tiles_per_side_; }
  static constexpr int packets_per_tile() { return (kTile / kPacket) * (kTile / kPacket); }

  // Fills lanes with texel indices y * N + x of packet p of tile t; returns how many (0..16).
  int packet_texels(int tile, int packet, std::array<int, 16>& lanes) const {
    const int tx = tile % tiles_per_side_, ty = tile / tiles_per_side_;
    const int px = packet % (kTile / kPacket), py = packet / (kTile / kPacket);
    const int x0 = tx * kTile + px * kPacket, y0 = ty * kTile + py * kPacket;
    int count = 0;
    for (int dy = 0; dy < kPacket; ++dy)
      for (int dx = 0; dx < kPacket; ++dx) {
        int x = x0 + dx, y = y0 + dy;
        if (x < n_ && y < n_) lanes[count++] = y * n_ + x;
      }
    return count;
  }
  // The same with each lane's texel coordinates as well.
  int packet_texels(int tile, int packet, std::array<int, 16>& lanes, std::array<int, 16>& xs,
                    std::array<int, 16>& ys) const {
    const int tx = tile % tiles_per_side_, ty = tile / tiles_per_side_;
    const int px = packet % (kTile / kPacket), py = packet / (kTile / kPacket);
    const int x0 = tx * kTile + px * kPacket, y0 = ty * kTile + py * kPacket;
    int count = 0;
    for (int dy = 0; dy < kPacket; ++dy)
      for (int dx = 0; dx < kPacket; ++dx) {
        int x = x0 + dx, y = y0 + dy;
        if (x < n_ && y < n_) {
          xs[count] = x;
          ys[count] = y;
          lanes[count++] = y * n_ + x;
        }
      }
    return count;
  }

 private:
  int n_;
  int tiles_per_side_;
};

}  // namespace clothbake::raycast
