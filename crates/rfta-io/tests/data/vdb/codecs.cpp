// Writes box.vdb's level set again with the codecs OpenVDB's Python module cannot choose, for
// rfta-io's reader tests. Build and run from this folder (Debian's libopenvdb-dev):
//
//   g++ -std=c++17 -O1 codecs.cpp -o /tmp/vdb-codecs -lopenvdb -ltbb -lImath && /tmp/vdb-codecs
//
// box-zip.vdb: zlib with active-mask compression; box-mask.vdb: active-mask compression and
// no codec (values stored as they are);
// box-double.vdb: the same values in a double grid (default Blosc compression).
#include <openvdb/openvdb.h>

static void write(const openvdb::GridBase::Ptr& grid, const char* path, uint32_t codec, bool set) {
    openvdb::io::File file(path);
    if (set) file.setCompression(codec);
    file.write({grid});
    file.close();
}

int main() {
    openvdb::initialize();
    openvdb::io::File in("box.vdb");
    in.open();
    auto box = openvdb::gridPtrCast<openvdb::FloatGrid>(in.readGrid("box"));
    in.close();
    write(box, "box-zip.vdb", openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK, true);
    write(box, "box-mask.vdb", openvdb::io::COMPRESS_ACTIVE_MASK, true);
    auto twice = openvdb::DoubleGrid::create(
        openvdb::DoubleTree::Ptr(new openvdb::DoubleTree(box->tree())));
    twice->setTransform(box->transform().copy());
    twice->setGridClass(openvdb::GRID_LEVEL_SET);
    twice->setName("box");
    write(twice, "box-double.vdb", 0, false);
    return 0;
}
