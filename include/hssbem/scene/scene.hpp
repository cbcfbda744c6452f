/// \file scene.hpp
/// Moved to session/scene.hpp: hssbem::Scene is a face of the session layer (scene_session.hpp).
/// Kept so that programs that include it still build; a forwarding header the layer check
/// allows (tests/check_layers.cmake).
#pragma once

#include "hssbem/session/scene.hpp"
