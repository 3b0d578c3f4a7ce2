// Pipeline construction for Renderer: one skinned pipeline per alpha mode (a specialization
// constant selects it, so OPAQUE keeps early depth testing), the same three for the MToon outline
// hull (a second constant), and one line pipeline, per target format / sample count / view mask. Cull mode, depth test and depth write are dynamic state.
#include <cstddef>
#include <string>
#include <vector>

#include "engine/renderer.h"
#include "shaders/lines_frag.spv.h"
#include "shaders/lines_vert.spv.h"
#include "shaders/skinned_frag.spv.h"
#include "shaders/skinned_vert.spv.h"

namespace embody::engine {

namespace {

struct PipelineDesc {
  VkShaderModule vert, frag;
  const VkSpecializationInfo* spec = nullptr;  // both stages (constant 0: alpha mode, 1: outline)
  bool lines = false;
  bool blend = false;
};

// Specialization constants of skinned.vert / skinned.frag.
struct SkinnedSpec {
  int32_t alphaMode = 0;
  VkBool32 outline = VK_FALSE;
};

// The render target a pipeline draws into (the fields of Renderer::PipelineKey).
struct PipelineTarget {
  VkFormat colorFormat, depthFormat;
  VkSampleCountFlagBits samples;
  uint32_t viewMask;
};

// The vertex buffer's layout: LineVertex for the line pipeline, avatar::SkinnedVertex otherwise.
struct VertexInput {
  VkVertexInputBindingDescription binding{0, 0, VK_VERTEX_INPUT_RATE_VERTEX};
  std::vector<VkVertexInputAttributeDescription> attrs;

  explicit VertexInput(bool lines) {
    if (lines) {
      binding.stride = sizeof(LineVertex);
      attrs = {{0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(LineVertex, position)},
               {1, 0, VK_FORMAT_R32G32B32A32_SFLOAT, offsetof(LineVertex, color)}};
    } else {
      using V = avatar::SkinnedVertex;
      binding.stride = sizeof(V);
      attrs = {{0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(V, position)},
               {1, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(V, normal)},
               {2, 0, VK_FORMAT_R32G32_SFLOAT, offsetof(V, uv)},
               {3, 0, VK_FORMAT_R32G32B32A32_UINT, offsetof(V, joints0)},
               {4, 0, VK_FORMAT_R32G32B32A32_UINT, offsetof(V, joints1)},
               {5, 0, VK_FORMAT_R32G32B32A32_SFLOAT, offsetof(V, weights0)},
               {6, 0, VK_FORMAT_R32G32B32A32_SFLOAT, offsetof(V, weights1)},
               {7, 0, VK_FORMAT_R32G32_SFLOAT, offsetof(V, uv1)}};
    }
  }

  VkPipelineVertexInputStateCreateInfo info() const {
    VkPipelineVertexInputStateCreateInfo vi{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    vi.vertexBindingDescriptionCount = 1;
    vi.pVertexBindingDescriptions = &binding;
    vi.vertexAttributeDescriptionCount = static_cast<uint32_t>(attrs.size());
    vi.pVertexAttributeDescriptions = attrs.data();
    return vi;
  }
};

VkPipelineColorBlendAttachmentState blendAttachment(bool blendOn) {
  constexpr VkColorComponentFlags kRgba =
      VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
  if (!blendOn) return {.colorWriteMask = kRgba};
  // Premultiplied by the shader's alpha, classic "over": colour src, dst, op; alpha src, dst, op.
  return {VK_TRUE, VK_BLEND_FACTOR_SRC_ALPHA, VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA, VK_BLEND_OP_ADD,
          VK_BLEND_FACTOR_ONE, VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA, VK_BLEND_OP_ADD, kRgba};
}

// One graphics pipeline for dynamic rendering into `t`; viewport, scissor, cull mode and depth
// test/write are dynamic state.
Result<UniquePipeline> createPipeline(VkDevice dev, VkPipelineLayout layout, const PipelineTarget& t,
                                      const PipelineDesc& d) {
  VkPipelineShaderStageCreateInfo stages[2] = {{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO},
                                               {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO}};
  stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
  stages[0].module = d.vert;
  stages[0].pName = "main";
  stages[0].pSpecializationInfo = d.spec;
  stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
  stages[1].module = d.frag;
  stages[1].pName = "main";
  stages[1].pSpecializationInfo = d.spec;

  const VertexInput input(d.lines);
  const VkPipelineVertexInputStateCreateInfo vi = input.info();
  VkPipelineInputAssemblyStateCreateInfo ia{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  ia.topology = d.lines ? VK_PRIMITIVE_TOPOLOGY_LINE_LIST : VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  vp.viewportCount = 1;
  vp.scissorCount = 1;
  VkPipelineRasterizationStateCreateInfo rs{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  rs.polygonMode = VK_POLYGON_MODE_FILL;
  // glTF winding; the projection flips y, the viewport does not.
  rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  rs.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  ms.rasterizationSamples = t.samples;
  VkPipelineDepthStencilStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  ds.depthCompareOp = VK_COMPARE_OP_LESS_OR_EQUAL;
  const VkPipelineColorBlendAttachmentState blend = blendAttachment(d.blend);
  VkPipelineColorBlendStateCreateInfo cb{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  cb.attachmentCount = 1;
  cb.pAttachments = &blend;
  const VkDynamicState dyn[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR,
                                VK_DYNAMIC_STATE_CULL_MODE, VK_DYNAMIC_STATE_DEPTH_TEST_ENABLE,
                                VK_DYNAMIC_STATE_DEPTH_WRITE_ENABLE};
  VkPipelineDynamicStateCreateInfo dy{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
  dy.dynamicStateCount = static_cast<uint32_t>(std::size(dyn));
  dy.pDynamicStates = dyn;
  VkPipelineRenderingCreateInfo rendering{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
  rendering.viewMask = t.viewMask;
  rendering.colorAttachmentCount = 1;
  rendering.pColorAttachmentFormats = &t.colorFormat;
  rendering.depthAttachmentFormat = t.depthFormat;

  VkGraphicsPipelineCreateInfo gci{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
  gci.pNext = &rendering;
  gci.stageCount = 2;
  gci.pStages = stages;
  gci.pVertexInputState = &vi;
  gci.pInputAssemblyState = &ia;
  gci.pViewportState = &vp;
  gci.pRasterizationState = &rs;
  gci.pMultisampleState = &ms;
  gci.pDepthStencilState = &ds;
  gci.pColorBlendState = &cb;
  gci.pDynamicState = &dy;
  gci.layout = layout;
  VkPipeline p = VK_NULL_HANDLE;
  if (VkResult r = vkCreateGraphicsPipelines(dev, VK_NULL_HANDLE, 1, &gci, nullptr, &p); r != VK_SUCCESS)
    return Error{std::string("vkCreateGraphicsPipelines: ") + vkResultName(r)};
  return UniquePipeline(dev, p);
}

}  // namespace

Status Renderer::init() {
  const VkDevice dev = device_.handle();
  auto sv = createShaderModule(dev, skinned_vert_spv, sizeof(skinned_vert_spv));
  auto sf = createShaderModule(dev, skinned_frag_spv, sizeof(skinned_frag_spv));
  auto lv = createShaderModule(dev, lines_vert_spv, sizeof(lines_vert_spv));
  auto lf = createShaderModule(dev, lines_frag_spv, sizeof(lines_frag_spv));
  if (!sv || !sf || !lv || !lf) return Error{"could not create the renderer's shader modules"};
  skinnedVert_ = std::move(sv).value();
  skinnedFrag_ = std::move(sf).value();
  linesVert_ = std::move(lv).value();
  linesFrag_ = std::move(lf).value();

  // set 0: scene block (views, light) + joint palette; set 1: a material's uniform block,
  // base-colour and emissive textures.
  // (+ bindings 3..5: morph target ranges, deltas and weights, shaders/morphing.glsl)
  VkDescriptorSetLayoutBinding sceneBindings[5] = {
      {0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, nullptr},
      {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, nullptr},
      {3, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, nullptr},
      {4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, nullptr},
      {5, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, nullptr}};
  VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  lci.bindingCount = 5;
  lci.pBindings = sceneBindings;
  VkDescriptorSetLayout layout = VK_NULL_HANDLE;
  if (vkCreateDescriptorSetLayout(dev, &lci, nullptr, &layout) != VK_SUCCESS) return Error{"descriptor set layout"};
  sceneLayout_ = UniqueDescriptorSetLayout(dev, layout);
  // The vertex stage reads the block and the outline-width texture (the outline hull); every
  // texture binding has the same stages so that one descriptor write fills them all.
  constexpr VkShaderStageFlags kMaterialStages = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
  VkDescriptorSetLayoutBinding materialBindings[1 + kMaterialTextureCount];
  materialBindings[0] = {0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, kMaterialStages, nullptr};
  for (uint32_t b = 1; b <= kMaterialTextureCount; ++b)
    materialBindings[b] = {b, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, kMaterialStages, nullptr};
  lci.bindingCount = 1 + kMaterialTextureCount;
  lci.pBindings = materialBindings;
  if (vkCreateDescriptorSetLayout(dev, &lci, nullptr, &layout) != VK_SUCCESS) return Error{"descriptor set layout"};
  materialLayout_ = UniqueDescriptorSetLayout(dev, layout);

  VkDescriptorSetLayout sets[2] = {sceneLayout_.get(), materialLayout_.get()};
  VkPushConstantRange push{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, 2 * sizeof(uint32_t)};
  VkPipelineLayoutCreateInfo pli{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pli.setLayoutCount = 2;
  pli.pSetLayouts = sets;
  pli.pushConstantRangeCount = 1;
  pli.pPushConstantRanges = &push;
  VkPipelineLayout pl = VK_NULL_HANDLE;
  if (vkCreatePipelineLayout(dev, &pli, nullptr, &pl) != VK_SUCCESS) return Error{"pipeline layout"};
  pipelineLayout_ = UniquePipelineLayout(dev, pl);
  return {};
}

Result<const Renderer::PipelineSet*> Renderer::pipelines(const PipelineKey& key) {
  if (auto it = pipelines_.find(key); it != pipelines_.end()) return &it->second;
  const auto [colorFormat, depthFormat, samples, viewMask] = key;

  const PipelineTarget target{colorFormat, depthFormat, samples, viewMask};
  auto build = [&](const PipelineDesc& d) -> Result<UniquePipeline> {
    auto p = createPipeline(device_.handle(), pipelineLayout_.get(), target, d);
    if (p) ++stats_.pipelinesCreated;
    return p;
  };

  PipelineSet set;
  const VkSpecializationMapEntry entries[2] = {{0, offsetof(SkinnedSpec, alphaMode), sizeof(int32_t)},
                                               {1, offsetof(SkinnedSpec, outline), sizeof(VkBool32)}};
  for (int32_t mode = 0; mode < 3; ++mode) {
    for (VkBool32 outline : {VK_FALSE, VK_TRUE}) {
      const SkinnedSpec values{mode, outline};
      const VkSpecializationInfo spec{2, entries, sizeof(values), &values};
      auto p = build({skinnedVert_.get(), skinnedFrag_.get(), &spec, false, mode == 2});
      if (!p) return Error{p.error()};
      UniquePipeline* slot[2][3] = {{&set.opaque, &set.mask, &set.blend},
                                    {&set.outlineOpaque, &set.outlineMask, &set.outlineBlend}};
      *slot[outline][mode] = std::move(p).value();
    }
  }
  auto lines = build({linesVert_.get(), linesFrag_.get(), nullptr, true, false});
  if (!lines) return Error{lines.error()};
  set.lines = std::move(lines).value();
  return &pipelines_.emplace(key, std::move(set)).first->second;
}

}  // namespace embody::engine
