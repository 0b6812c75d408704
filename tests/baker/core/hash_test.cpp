#include "lodbake/core/hash.h"

#include <gtest/gtest.h>

#include "lodbake/core/mesh.h"
#include "mesh_builders.h"

using namespace lodbake;

TEST(HashTest, SplitFeedingMatchesOneShot) {
    const std::string text = "The quick brown fox jumps over the lazy dog, twice over.";
    Hasher one;
    one.addBytes(text.data(), text.size());
    for (size_t split = 0; split <= text.size(); ++split) {
        Hasher two;
        two.addBytes(text.data(), split);
        two.addBytes(text.data() + split, text.size() - split);
        EXPECT_EQ(one.digest(), two.digest()) << split;
    }
}

TEST(HashTest, SensitiveToEveryByteAndLength) {
    std::string a(33, 'x');
    Hasher h0;
    h0.addBytes(a.data(), a.size());
    for (size_t i = 0; i < a.size(); ++i) {
        std::string b = a;
        b[i] = 'y';
        Hasher h;
        h.addBytes(b.data(), b.size());
        EXPECT_NE(h.digest(), h0.digest()) << i;
    }
    Hasher shorter;
    shorter.addBytes(a.data(), a.size() - 1);
    EXPECT_NE(shorter.digest(), h0.digest());
}

TEST(HashTest, MeshHashSeesPositionsIndicesAndMaterials) {
    const Mesh base = lodbake_test::tetrahedron();
    const uint64_t h = hashMesh(base);
    EXPECT_EQ(h, hashMesh(lodbake_test::tetrahedron()));
    Mesh m = base;
    m.positions[0].x = -0.0f; // sign of zero is content
    EXPECT_NE(hashMesh(m), h);
    m = base;
    std::swap(m.indices[0], m.indices[1]);
    EXPECT_NE(hashMesh(m), h);
    m = base;
    m.materials.push_back(Material());
    EXPECT_NE(hashMesh(m), h);
}

TEST(HashTest, HexIsSixteenDigits) {
    EXPECT_EQ(hashToHex(0), "0000000000000000");
    EXPECT_EQ(hashToHex(0xabcdef0123456789ull), "abcdef0123456789");
}
