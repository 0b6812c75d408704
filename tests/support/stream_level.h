#pragma once
// A level's stream coded as the bake codes it: the encoder's prepare step, then the commit it returns.

#include <cstddef>

#include "lodbake/pack/pack.h"

namespace lodbake_test {

inline lodbake::Status encodeStreamLevel(const lodbake::PackStreamEncoder& encoder, const lodbake::LodChain& chain,
                                         size_t level_index, lodbake::PackLevel& level) {
    LODBAKE_ASSIGN_OR_RETURN(lodbake::PackStreamCommit commit, encoder.prepare(chain, level_index, level.mesh));
    return commit ? commit(level) : lodbake::Status::okStatus();
}

} // namespace lodbake_test
