// Everything of the whisking controller library in one include.
#pragma once

#include <whiskeye/rcp/contact_detector.h>
#include <whiskeye/rcp/controller.h>
#include <whiskeye/rcp/cycle_assembler.h>
#include <whiskeye/rcp/experiment.h>
#include <whiskeye/rcp/params.h>
#include <whiskeye/rcp/pattern.h>
#include <whiskeye/rcp/plant.h>
#include <whiskeye/rcp/types.h>
