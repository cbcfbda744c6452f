/// \file contact_scene.hpp
/// Moved to session/contact_scene.hpp: hssbem::ContactScene is a face of the session layer
/// (contact_session.hpp). Kept so that programs that include it still build; a forwarding
/// header the layer check allows (tests/check_layers.cmake).
#pragma once

#include "hssbem/session/contact_scene.hpp"
