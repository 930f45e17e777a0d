// hmsm: physically based tree animation in wind (Yang & Wu 2011, the HMSM).
// The one header an engine includes.
#pragma once

#include <hmsm/config.h>
#include <hmsm/generator.h>
#include <hmsm/hierarchy.h>
#include <hmsm/import.h>
#include <hmsm/levels.h>
#include <hmsm/mesh.h>
#include <hmsm/options.h>
#include <hmsm/pass.h>
#include <hmsm/scene.h>
#include <hmsm/schedule.h>
#include <hmsm/simulation.h>
#include <hmsm/skin.h>
#include <hmsm/species.h>
#include <hmsm/status.h>
#include <hmsm/tree.h>
