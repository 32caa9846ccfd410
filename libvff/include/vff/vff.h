// vff/vff.h - everything in libvff. See README.md for an overview and spec/ for the format.
#pragma once

#include "vff/bc4.h"
#include "vff/direction.h"
#include "vff/encoding.h"
#include "vff/error.h"
#include "vff/export.h"
#include "vff/format.h"
#include "vff/positions.h"
#include "vff/query.h"
#include "vff/refine.h"
#include "vff/reader.h"
#include "vff/scene.h"
#include "vff/scene_description.h"
#include "vff/validate.h"
#include "vff/version.h"
#include "vff/writer.h"
