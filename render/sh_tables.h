#pragma once
/// The ShTables uniform (shaders/shared/sh_tables.h) that every shader evaluating core/sh.h's
/// basis or its clamped-cosine convolution binds.

#include "shaders/shared/sh_tables.h"

namespace pic::gpu {

/// shRecurrence's constants and clampedCosineZonal's K_l, packed as the shaders read them.
ShTables makeShTables();

}  // namespace pic::gpu
